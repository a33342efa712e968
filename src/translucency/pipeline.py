"""The main job: what `make demo` / `translucency demo` runs on the embedded default data.

1. compares the dipole, Christensen–Burley and a least-squares exponential
   fit of the dipole for every material of Jensen's table, and writes a model
   file of those fits;
2. reads the embedded default measurement (a virtual DISCO scan of the
   generated marble sample) and fits the three profile families to the ring
   profiles of a few incident points (the paper's Figure 1, left).

Later stages (planar fits with α, meshes) extend it.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from .data import default_dataset_path
from .evaluate.baselines import material_profiles, plot_profiles
from .evaluate.measured import BANDS, measured_profile, plot_measured
from .io.dataset import open_dataset
from .io.atomic import atomic_path, write_json
from .io.model_file import save_model
from .model import MATERIALS, ExponentialModel, PlanarAlpha


def run_demo(out_dir, *, n_terms: int = 3, step: Callable[[str], None] | None = None, dataset=None) -> dict:
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
    ``measured_profiles.png``, ``measured_profiles.json``
        Ring profiles of the default data set (``dataset`` overrides it) at
        four incident points with exponential, dipole and Burley fits, and
        their relative errors per distance band.

    Returns
    -------
    dict
        Paths of the outputs.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
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
    mpath = save_model(model, out_dir / "dipole_fits.model.zip",
                       meta={"materials": list(MATERIALS), "source": "3-term fits of the Jensen 2001 dipole"})

    # -- the embedded measurement: Figure 1 (left) ------------------------------------
    ds = open_dataset(dataset or default_dataset_path())
    n = int(np.sqrt(ds.n_points))
    picks = sorted({0, n // 2 * n + n // 2, n * (n // 4) + 3 * n // 4, ds.n_points - 1})
    measured = []
    for p in picks:
        if step:
            step(f"measured point {p}")
        measured.append(measured_profile(ds, p, channel=1, n_terms=n_terms))
    mpng = out_dir / "measured_profiles.png"
    with atomic_path(mpng) as tmp:
        plot_measured(measured, tmp, f"{ds.path.name}: ring profiles around incident points and fitted models")
    mjs = write_json(out_dir / "measured_profiles.json", {
        "dataset": str(ds.path), "bands_mm": {k: list(v) for k, v in BANDS.items()}, "channel": "G",
        "points": {str(m.point): {w: m.band_errors(w) for w in ("exponential", "dipole", "burley")}
                   for m in measured}})
    return {"figure": png, "summary": js, "model": mpath, "measured": mpng, "measured_summary": mjs}
