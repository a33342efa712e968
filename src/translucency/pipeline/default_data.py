"""The embedded data of Figure 1: the sample, the scan, its held-out truth and the fine near-x_i profiles.

Made by :func:`write_default_data` (``make default-data``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..acquire.planar import PlanarSetup, acquire_planar
from ..acquire.samples import make_sample
from ..acquire.transport import TOP, random_walk
from ..acquire.volume import Volume
from ..data import DATA_DIR
from ..io.atomic import atomic_path
from ..io.dataset import open_dataset

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

    Examples
    --------
    >>> v = demo_volume((8.0, 8.0, 2.0), band_y_mm=4.0)   # a small one: 8 × 8 × 2 mm, the band above y = 4 mm
    >>> v.sigma_s.shape   # (Z, Y, X, RGB), 0.25 mm voxels
    (8, 32, 32, 3)
    >>> v.sigma_s[0, 16:24, 0, 1].round(2)   # green σ_s (mm⁻¹) up the band: clear lamellae at 0.16
    array([4.19, 0.16, 0.16, 4.19, 4.19, 0.16, 0.16, 4.19], dtype=float32)
    >>> np.unique(v.sigma_s[:, 17, :, 1]).round(2)   # a lamella is clear along x and through the depth
    array([0.16], dtype=float32)
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
    """The :class:`PlanarSetup` of the embedded ``"fit"`` data or of its held-out ``"truth"``.

    Examples
    --------
    >>> fit, truth = default_setup("fit"), default_setup("truth")
    >>> fit.grid, fit.window_pixels(), fit.dtype   # 1024 points, 33 × 33-pixel windows, as stored
    ((32, 32), 33, 'float16')
    >>> (fit.photons, fit.seed), (truth.photons, truth.seed)   # the truth: 3× the photons, another seed
    ((20000, 1), (60000, 2))
    """
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
    marble between lamellae in the band (by the surface voxel's absorption and scattering).

    Examples
    --------
    >>> v = demo_volume((8.0, 8.0, 2.0), band_y_mm=4.0)
    >>> g = np.arange(0.625, 8.0, 0.5)
    >>> x_i = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)   # 16 × 16 points 0.5 mm apart
    >>> cols, rows = (x_i[profile_points(x_i, v, band_y_mm=4.0)] / v.voxel_mm).astype(int).T
    >>> v.sigma_a[0, rows, cols, 1].astype(float).round(4).tolist()  # green σ_a: the least, the most (a vein)
    [0.0041, 0.0144, 0.002, 0.0041]
    >>> v.sigma_s[0, rows, cols, 1].astype(float).round(2).tolist()  # σ_s: a clear lamella, the band's marble
    [2.62, 2.25, 0.16, 4.19]
    """
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

    Examples
    --------
    >>> from translucency.acquire import Volume
    >>> slab = Volume.homogeneous((8, 16, 16), 0.25, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3)
    >>> prof = fine_profiles(slab, np.array([[2.0, 2.0]]), [0], photons=100, seed=3, bin_mm=0.5, r_max_mm=2.0)
    >>> prof["edges_mm"].tolist(), prof["R_d"].shape   # 4 rings, (points, rings, RGB) in mm⁻²
    ([0.0, 0.5, 1.0, 1.5, 2.0], (1, 4, 3))
    >>> share = (prof["R_d"][0] * np.pi * np.diff(prof["edges_mm"] ** 2)[:, None]).sum(axis=0)
    >>> bool(((share > 0) & (share <= 1)).all())   # the share of the photons leaving within 2 mm
    True
    """
    edges = np.arange(0.0, r_max_mm + 1e-9, bin_mm)
    area = np.pi * np.diff(edges**2)
    xy = x_i[list(points)]
    R = np.zeros((len(points), len(edges) - 1, 3))
    var = np.zeros_like(R)
    for channel in range(3):
        res = random_walk(volume, channel, xy, photons, seed=seed)
        which = np.arange(len(points)).repeat(photons)
        top = res.code == TOP
        r = np.hypot(res.x[top] - xy[which[top], 0], res.y[top] - xy[which[top], 1])
        for k in range(len(points)):
            n = np.histogram(r[which[top] == k], edges)[0].astype(float)
            p = n / photons
            R[k, :, channel] = p / area
            var[k, :, channel] = p * (1 - p) / photons / area**2
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
    (default: the package's data folder).  About 10 minutes on 2 quiet cores.

    Parameters
    ----------
    folder : str or Path, optional
        Where the three files go (default :data:`translucency.data.DATA_DIR`).
    overwrite : bool
        Replace data sets already there.

    Returns
    -------
    dict
        The paths written: ``fit``, ``truth`` (planar data sets) and ``fine`` (the profiles, ``.npz``).

    Examples
    --------
    The shipped scan is what :data:`DEFAULT_SCAN` and :data:`DEFAULT_ACQUISITIONS` say: 32 × 32 points,
    0.25 mm pixels, 8 mm windows (33 pixels, odd), 20,000 photons with seed 1:

    >>> ds = open_dataset(DATA_DIR / "marble_default.zarr")
    >>> ds.header["n_points"], ds.pitch, ds.window
    (1024, 0.25, (33, 33))
    >>> (ds.header["acquisition"]["photons"], ds.header["acquisition"]["seed"]) == DEFAULT_ACQUISITIONS["fit"]
    True

    Made again elsewhere (about 10 minutes):

    >>> import tempfile
    >>> out = write_default_data(tempfile.mkdtemp())  # doctest: +SKIP
    >>> sorted(out), out["fine"].name  # doctest: +SKIP
    (['fine', 'fit', 'truth'], 'marble_default_fine_profiles.npz')
    """
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
