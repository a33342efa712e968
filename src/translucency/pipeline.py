"""The main job: what `make demo` / `translucency demo` runs on the embedded default data.

Today it compares the dipole, Christensen–Burley and a least-squares
exponential fit of the dipole for every material of Jensen's table, and
writes a model file of those fits.  Later stages (virtual acquisition, planar
fits, meshes) extend it.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from .evaluate.baselines import material_profiles, plot_profiles
from .io.atomic import atomic_path, write_json
from .io.model_file import save_model
from .model import MATERIALS, ExponentialModel, PlanarAlpha


def run_demo(out_dir, *, n_terms: int = 3, step: Callable[[str], None] | None = None) -> dict:
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
    return {"figure": png, "summary": js, "model": mpath}
