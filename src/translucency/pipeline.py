"""The main job: what `make demo` / `translucency demo` runs on the embedded default data.

1. compares the dipole, Christensen–Burley and a least-squares exponential
   fit of the dipole for every material of Jensen's table, and writes a model
   file of those fits;
2. fits the embedded default measurement (a virtual DISCO scan of the
   generated marble sample with a fibrous band, :func:`demo_volume`) per
   incident point with α — isotropic and anisotropic exponentials, the dipole
   and Christensen–Burley — and writes the evaluation report with the paper's
   Figure 1 (profiles and error maps), every model against an independent
   acquisition of the same sample and points (the held-out truth).

The embedded data are made by :func:`write_default_data` (``make default-data``).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from .acquire.mesh import acquire_mesh, object_volume
from .acquire.objects import make_pig
from .acquire.pattern import acquire_pattern
from .acquire.planar import PlanarSetup, acquire_planar
from .acquire.samples import make_sample, sample_of_dataset
from .acquire.transport import TOP, random_walk
from .acquire.volume import Volume
from .data import DATA_DIR, default_dataset_path, default_fine_profiles_path, default_truth_path
from .evaluate.baselines import material_profiles, plot_profiles
from .evaluate.relight import pattern_irradiance, plot_relighting, relight
from .evaluate.report import write_report
from .fit.mesh import fit_mesh
from .fit.planar import fit_planar
from .io.atomic import atomic_path, write_json
from .io.dataset import open_dataset
from .io.model_file import save_model
from .io.outputs import claim_folder
from .model import MATERIALS, ExponentialModel, PlanarAlpha
from .render import Camera, PointLight
from .render.figure import figure2
from .render.picture import coverage
from .render.reference import SHIPPED as SHIPPED_REFERENCES
from .render.reference import converged_reference

#: the models' pairs are summed out to this many half-windows: light that crosses the grid from a lit
#: cell (half a window only reached 0.84 × the reference's total on the fibrous band; 4 reach 0.93)
RELIGHT_RADIUS_WINDOWS = 4


def relight_check(
    ds,
    models: dict,
    figure,
    *,
    pattern: str = "stripe",
    photons: int = 1000,
    seed: int = 5,
    volume: Volume | None = None,
) -> dict:
    """Relight the data set's sample with each model and with photon transport; plot and compare.

    The light falls on the cells of the incident grid (side = grid spacing);
    the exitance is compared on the data set's pixel grid over the scanned area
    plus a margin of half a window.
    """
    x_i = ds["x_i"].astype(np.float64)
    spacing = float(np.min(np.diff(np.unique(x_i[:, 0]))))
    E = pattern_irradiance(pattern, x_i)
    margin = ds.pitch * (ds.window[1] // 2)
    origin = x_i.min(axis=0) - margin
    shape = tuple(int(round((np.ptp(x_i[:, k]) + 2 * margin) / ds.pitch)) for k in (1, 0))
    reference = acquire_pattern(
        volume if volume is not None else sample_of_dataset(ds.header),
        x_i,
        spacing,
        E,
        origin,
        ds.pitch,
        shape,
        photons=photons,
        seed=seed,
    )
    preds = {
        name: relight(m, E, spacing**2, origin, ds.pitch, shape, radius=RELIGHT_RADIUS_WINDOWS * margin)
        for name, m in models.items()
    }
    extent = [origin[0], origin[0] + shape[1] * ds.pitch, origin[1], origin[1] + shape[0] * ds.pitch]
    errors = plot_relighting(reference, preds, extent, figure)
    total = float(reference.sum())
    return {
        "pattern": pattern,
        "photons_per_entry": photons,
        "rel_l2": errors,
        "total_ratio": {n: float(B.sum() / total) for n, B in preds.items()},
    }


#: samples per pixel of each of the two reference renders of Figure 2 (its noise: figure2.json)
FIGURE2_REFERENCE_SPP = 256


def figure2_scene(size=(160, 120)):
    """The main job's object: the pig filled with veined marble (1 mm voxels, seed 1), light, camera."""
    pig = make_pig()
    volume = object_volume("marble", pig, 1.0, seed=1)
    light = PointLight((60.0, -80.0, 120.0), 2.0e4)
    return pig, volume, light, Camera.looking_at(pig, width=size[0], height=size[1])


def run_figure2(
    report_dir,
    data_path,
    model_path,
    *,
    points: int = 96,
    photons: int = 8000,
    spp: int = FIGURE2_REFERENCE_SPP,
    size=(160, 120),
    overwrite: bool = False,
) -> dict:
    """Acquire the pig per vertex (index-matched, so that volpath can light it), fit, render, compare.

    Writes the mesh data set to ``data_path`` (resumed, or reused, if it holds the same acquisition), the
    per-vertex model to ``model_path`` (replacing an earlier one with ``overwrite``) and Figure 2 into
    ``report_dir``.  The reference is the mean of two ``spp``-sample volpath renders, shipped with the
    package for the default arguments (``make default-reference`` makes it again).
    """
    pig, volume, light, camera = figure2_scene(size)
    acquire_mesh(
        pig,
        volume,
        data_path,
        n_points=points,
        photons=photons,
        chunk_points=16,
        index_matched=True,
        overwrite=overwrite,
    )
    fit = fit_mesh(data_path, "iso")
    save_model(
        fit.model,
        model_path,
        dtype="float16",
        overwrite=overwrite,
        meta=fit.metadata(Path(data_path).resolve()),
    )
    return figure2(fit.model, pig, light, report_dir, volume=volume, camera=camera, spp_reference=spp)


def write_figure2_reference(folder=None, *, spp: int = FIGURE2_REFERENCE_SPP, size=(160, 120)) -> dict:
    """Render the main job's converged reference into ``folder`` (default: the shipped references)."""
    pig, volume, light, camera = figure2_scene(size)
    _, info = converged_reference(
        pig, volume, light, camera, coverage(pig, camera), spp=spp, cache=folder or SHIPPED_REFERENCES
    )
    return info


# -- the embedded default data (Figure 1) ----------------------------------------------------------

#: the generated sample of the embedded data: the ``marble`` generator's slab (seed 1) with a fibrous band
DEFAULT_SAMPLE = {"size_mm": (32.0, 32.0, 10.0), "voxel_mm": 0.25, "seed": 1, "band_y_mm": 17.0}
#: the scan: 32 x 32 incident points 0.5 mm apart over the central 16 mm, 0.25 mm pixels, 8 mm windows
DEFAULT_SCAN = {"grid": 32, "span_mm": 16.0, "pitch_mm": 0.25, "window_mm": 8.0}
#: photons per point and channel and photon seed of the fitted data and of the held-out truth (same sample)
DEFAULT_ACQUISITIONS = {"fit": (20_000, 1), "truth": (60_000, 2)}
#: the near-x_i profiles on a fine radial grid (ring tally of the exits, no pixels)
FINE_PROFILES = {"photons": 400_000, "seed": 3, "bin_mm": 0.05, "r_max_mm": 2.0}


def demo_volume(
    size_mm=DEFAULT_SAMPLE["size_mm"],
    voxel_mm: float = DEFAULT_SAMPLE["voxel_mm"],
    seed: int = DEFAULT_SAMPLE["seed"],
    band_y_mm: float = DEFAULT_SAMPLE["band_y_mm"],
) -> Volume:
    """The sample of the embedded data: veined marble with a fibrous band (the anisotropic model's case).

    Below ``y = band_y_mm`` it is the ``marble`` generator's slab (white body, grey-green veins); above,
    clear lamellae (σ_s = 0.15 mm⁻¹, 0.5 mm wide, 1 mm pitch in y, the full depth) alternate with the
    veined marble scattering 1.6× more: light channels along x, so R_d spreads farther along x than y.
    The coefficients vary across y but not along x in the band.
    """
    vol = make_sample("marble", size_mm, voxel_mm, seed=seed)
    y = (np.arange(vol.sigma_s.shape[1]) + 0.5) * voxel_mm
    band = y >= band_y_mm
    clear = band & (np.cos(2 * np.pi * (y - band_y_mm)) < 0.0)
    s, a = vol.sigma_s.copy(), vol.sigma_a.copy()
    s[:, band] *= 1.6
    s[:, clear] = np.array([0.150, 0.160, 0.140], np.float32)
    a[:, clear] = np.array([0.003, 0.002, 0.006], np.float32)
    description = {
        "composite": "marble with a fibrous band (translucency.pipeline.demo_volume)",
        "seed": seed,
        "band_y_mm": band_y_mm,
        "g": 0.0,
    }
    return Volume(s, a, voxel_mm, 0.0, vol.eta, description)


def default_setup(which: str) -> PlanarSetup:
    """The :class:`PlanarSetup` of the embedded ``"fit"`` data or of its held-out ``"truth"``."""
    photons, seed = DEFAULT_ACQUISITIONS[which]
    sc = DEFAULT_SCAN
    return PlanarSetup(
        grid=(sc["grid"], sc["grid"]),
        span=(sc["span_mm"], sc["span_mm"]),
        pitch=sc["pitch_mm"],
        window=sc["window_mm"],
        photons=photons,
        seed=seed,
        chunk_points=64,
        dtype="float16",
    )


def profile_points(x_i: np.ndarray, volume: Volume, band_y_mm: float = DEFAULT_SAMPLE["band_y_mm"]):
    """Four incident points for Figure 1's profiles: clean marble, a vein, a clear lamella and the
    marble between lamellae in the band (by the surface voxel's absorption and scattering)."""
    v = volume.voxel_mm
    row = np.clip((x_i[:, 1] / v).astype(int), 0, volume.sigma_a.shape[1] - 1)
    col = np.clip((x_i[:, 0] / v).astype(int), 0, volume.sigma_a.shape[2] - 1)
    sa = volume.sigma_a[0, row, col, 1]
    ss = volume.sigma_s[0, row, col, 1]
    lo, hi = x_i.min(0) + 1.0, x_i.max(0) - 1.0
    inner = (x_i >= lo).all(1) & (x_i <= hi).all(1)
    below = inner & (x_i[:, 1] < band_y_mm - 1.0)
    above = inner & (x_i[:, 1] > band_y_mm + 1.0)
    pick = lambda sel, key: int(np.flatnonzero(sel)[np.argmin(key[sel])])  # noqa: E731
    return [pick(below, sa), pick(below, -sa), pick(above, ss), pick(above, -ss)]


def fine_profiles(
    volume: Volume, x_i: np.ndarray, points, *, photons: int, seed: int, bin_mm: float, r_max_mm: float
) -> dict:
    """Ring-averaged R_d(r) around ``points`` on a fine radial grid, straight from the photon exits.

    R_d of a ring = exits in it / (N · ring area); its variance p̂(1 − p̂)/(N · area²).  Per channel.
    """
    edges = np.arange(0.0, r_max_mm + 1e-9, bin_mm)
    area = np.pi * np.diff(edges**2)
    xy = x_i[list(points)]
    R = np.zeros((len(points), len(edges) - 1, 3))
    var = np.zeros_like(R)
    for ch in range(3):
        res = random_walk(volume, ch, xy, photons, seed=seed)
        which = np.arange(len(points)).repeat(photons)
        top = res.code == TOP
        r = np.hypot(res.x[top] - xy[which[top], 0], res.y[top] - xy[which[top], 1])
        for k in range(len(points)):
            n = np.histogram(r[which[top] == k], edges)[0].astype(float)
            p = n / photons
            R[k, :, ch] = p / area
            var[k, :, ch] = p * (1 - p) / photons / area**2
    return {
        "edges_mm": edges,
        "points": np.asarray(points),
        "x_i": xy,
        "R_d": R,
        "variance": var,
        "photons": photons,
        "seed": seed,
    }


def write_default_data(folder=None, *, overwrite: bool = True) -> dict:
    """Make the embedded data (``make default-data``): the fitted scan, its held-out truth (the same
    sample, another photon seed, 3x the photons) and the fine near-x_i profiles, into ``folder``
    (default: the package's data folder).  About 10 minutes on 2 quiet cores."""
    folder = Path(folder or DATA_DIR)
    vol = demo_volume()
    out = {}
    for which, name in (("fit", "marble_default.zarr"), ("truth", "marble_default_truth.zarr")):
        acquire_planar(vol, default_setup(which), folder / name, overwrite=overwrite)
        out[which] = folder / name
    x_i = open_dataset(out["fit"])["x_i"].astype(np.float64)
    prof = fine_profiles(
        vol,
        x_i,
        profile_points(x_i, vol),
        **{
            "photons": FINE_PROFILES["photons"],
            "seed": FINE_PROFILES["seed"],
            "bin_mm": FINE_PROFILES["bin_mm"],
            "r_max_mm": FINE_PROFILES["r_max_mm"],
        },
    )
    out["fine"] = folder / "marble_default_fine_profiles.npz"
    with atomic_path(out["fine"]) as tmp:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **prof)
    return out


#: the planar fits of the main job: label -> fit_planar arguments
DEMO_FITS = {
    "iso": dict(model="iso"),
    "aniso": dict(model="aniso", n_directions=8),
    "dipole": dict(model="dipole"),
    "burley": dict(model="burley"),
}


def run_demo(
    out_dir,
    *,
    n_terms: int = 3,
    step: Callable[[str], None] | None = None,
    dataset=None,
    max_rounds: int = 3,
    overwrite: bool = False,
) -> dict:
    """Run the main job and write its outputs under ``out_dir``.

    Outputs
    -------
    ``baselines.png``
        R_d(r) of dipole, exponential fit and Burley per material (green channel).
    ``baselines.json``
        Totals and relative differences per material and channel.
    ``dipole_fits.model.zip``
        The exponential fits as a per-channel model file: one incident point
        per material, 1 mm apart along x (``meta["materials"]`` names them).
    ``fits/<label>.model.zip``
        The planar fits of the default data set (``dataset`` overrides it):
        iso, aniso (m = 8), dipole and Burley, each with its α.
    ``report/``
        Their evaluation (:func:`translucency.evaluate.report.write_report`)
        against the embedded held-out truth (the same sample and incident
        points, an independent acquisition with 3x the photons; the default
        data only): Figure 1's profiles with residuals and the fine near-x_i
        rings, error maps, α, parameters, ``report.json`` and ``index.html``.

    ``out_dir`` must be new, empty, or an earlier output folder of the tool
    (then only with ``overwrite``): :func:`translucency.io.outputs.claim_folder`.

    Returns
    -------
    dict
        Paths of the outputs.
    """
    out_dir = claim_folder(out_dir, overwrite=overwrite, inputs=[dataset])
    profiles = []
    for name, mat in MATERIALS.items():
        if step:
            step(name)
        profiles.append(material_profiles(mat, n_terms=n_terms))

    png = out_dir / "baselines.png"
    with atomic_path(png) as tmp:
        plot_profiles(profiles, tmp)
    summary = {p.material.name: p.summary() for p in profiles}
    js = write_json(out_dir / "baselines.json", {"units": {"r": "mm", "R_d": "mm^-2"}, "materials": summary})

    # the fits as one per-channel exponential model (C = 3, m = 1)
    n = len(profiles)
    c = np.array([[[f.c] for f in p.fits] for p in profiles])  # (N, 3, 1, n)
    d = np.array([[[f.d] for f in p.fits] for p in profiles])
    x_i = np.stack([np.arange(n, dtype=float), np.zeros(n)], axis=1)
    model = ExponentialModel(x_i, c, d, PlanarAlpha.uniform((1, n), origin=(-0.5, -0.5), pitch=1.0))
    mpath = save_model(
        model,
        out_dir / "dipole_fits.model.zip",
        overwrite=True,
        meta={"materials": list(MATERIALS), "source": "3-term fits of the Jensen 2001 dipole"},
    )

    # -- the embedded measurement: planar fits and Figure 1 -------------------------
    ds = open_dataset(dataset or default_dataset_path())
    embedded = dataset is None  # the default data come with their held-out truth and fine profiles
    truth = open_dataset(default_truth_path()) if embedded else None
    models, flagged = {}, {}
    for label, kw in DEMO_FITS.items():
        if step:
            step(f"fit {label}")
        fit = fit_planar(ds, n_terms=n_terms, max_rounds=max_rounds, **kw)
        save_model(
            fit.model, out_dir / "fits" / f"{label}.model.zip", overwrite=True, meta=fit.metadata(ds.path)
        )
        models[label], flagged[label] = fit.model, fit.flagged
    # -- relighting: a stripe of light, models against photon transport ------------------
    if step:
        step("relighting")
    relit = relight_check(
        ds,
        {k: models[k] for k in ("iso", "dipole")},
        out_dir / "report" / "relight.png",
        volume=demo_volume() if embedded else None,
    )
    write_json(out_dir / "report" / "relight.json", relit)
    if step:
        step("report")
    # -- Figure 2: the pig, acquired per vertex, fitted, rendered beside volpath ------------
    if step:
        step("figure 2")
    fig2 = run_figure2(
        out_dir / "report", out_dir / "pig.zarr", out_dir / "fits" / "pig_iso.model.zip", overwrite=True
    )
    write_report(
        models,
        ds,
        out_dir / "report",
        flagged=flagged,
        truth=truth,
        fine=default_fine_profiles_path() if embedded else None,
        extra=[
            (
                "relight.png",
                "Relighting: the sample under a 2 mm stripe of light, photon transport (reference) against "
                "the fitted models (superposition of R_d over the incident cells); green channel.",
            ),
            (
                "figure2.png",
                "Figure 2: the procedural alabaster pig (generated marble filling, index-matched), "
                "path-traced by Mitsuba volpath (left) and rendered from the per-vertex model fitted to its "
                f"virtual acquisition (middle); FLIP {fig2['flip_mean_object']:.3f}, "
                f"relative RMSE {fig2['rel_rmse']:.2f} over the object; "
                "by region (relative RMSE, pixels): "
                + ", ".join(
                    f"{k} {v['rel_rmse']:.2f} ({v['pixels']})"
                    for k, v in fig2["regions"].items()
                    if k != "all"
                )
                + ".",
            ),
        ],
    )
    return {
        "figure": png,
        "summary": js,
        "model": mpath,
        "fits": out_dir / "fits",
        "pig": out_dir / "pig.zarr",
        "report": out_dir / "report" / "index.html",
    }
