"""The main job: what `make demo` / `translucency demo` runs on the embedded default data.

1. compares the dipole, Christensen–Burley and a least-squares exponential
   fit of the dipole for every material of Jensen's table, and writes a model
   file of those fits;
2. fits the embedded default measurement (a virtual DISCO scan of the
   generated marble sample) per incident point with α — isotropic and
   anisotropic exponentials, the dipole and Christensen–Burley — and writes
   the evaluation report with the paper's Figure 1 (profiles and error maps).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from .data import default_dataset_path
from .evaluate.baselines import material_profiles, plot_profiles
from .evaluate.report import write_report
from .fit.planar import fit_planar
from .io.dataset import open_dataset
from .io.atomic import atomic_path, write_json
from .io.model_file import save_model
from .model import MATERIALS, ExponentialModel, PlanarAlpha


#: the planar fits of the main job: label -> fit_planar arguments
DEMO_FITS = {
    "iso": dict(model="iso"),
    "aniso": dict(model="aniso", n_directions=8),
    "dipole": dict(model="dipole"),
    "burley": dict(model="burley"),
}


def run_demo(out_dir, *, n_terms: int = 3, step: Callable[[str], None] | None = None, dataset=None,
             max_rounds: int = 3) -> dict:
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
        Their evaluation (:func:`translucency.evaluate.report.write_report`):
        Figure 1's profiles and error maps, α, parameters, ``report.json``
        and ``index.html``.

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

    # -- the embedded measurement: planar fits and Figure 1 -------------------------
    ds = open_dataset(dataset or default_dataset_path())
    models, flagged = {}, {}
    for label, kw in DEMO_FITS.items():
        if step:
            step(f"fit {label}")
        fit = fit_planar(ds, n_terms=n_terms, max_rounds=max_rounds, **kw)
        save_model(fit.model, out_dir / "fits" / f"{label}.model.zip",
                   meta={"dataset": str(ds.path), "fit": fit.options, "objective_per_round": fit.history,
                         "seconds": round(fit.seconds, 2), "flagged_points": np.flatnonzero(fit.flagged).tolist()})
        models[label], flagged[label] = fit.model, fit.flagged
    if step:
        step("report")
    write_report(models, ds, out_dir / "report", flagged=flagged)
    return {"figure": png, "summary": js, "model": mpath, "fits": out_dir / "fits",
            "report": out_dir / "report" / "index.html"}
