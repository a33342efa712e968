"""The main job: what `make demo` / `translucency demo` runs on the embedded default data.

1. compares the dipole, Christensen–Burley and a least-squares exponential
   fit of the dipole for every material of Jensen's table, and writes a model
   file of those fits;
2. fits the embedded default measurement (a virtual DISCO scan of the
   generated marble sample with a fibrous band, :func:`~.default_data.demo_volume`) per
   incident point with α — isotropic and anisotropic exponentials, the dipole
   and Christensen–Burley — and writes the evaluation report with the paper's
   Figure 1 (profiles and error maps), every model against an independent
   acquisition of the same sample and points (the held-out truth);
3. relights the sample (:mod:`.relight_check`) and makes Figure 2 (:mod:`.figure2`).
"""

from __future__ import annotations

import itertools
import json
import numbers
from collections.abc import Callable

from .._validate import TranslucencyError
from ..data import default_dataset_path, default_fine_profiles_path, default_truth_path
from ..evaluate.baselines import fits_model, material_profiles, plot_profiles
from ..evaluate.report import write_report
from ..fit.planar import fit_planar
from ..io.atomic import atomic_path, write_json
from ..io.dataset import open_dataset
from ..io.model_file import read_header, save_model
from ..io.outputs import claim_folder
from ..model import MATERIALS
from ..render.compare import FLIP_SKIPPED, flip_available
from ..resources.run import Reporter
from .default_data import demo_volume
from .figure2 import run_figure2
from .relight_check import relight_check

#: the planar fits of the main job: label -> fit_planar arguments.  "default" is what ``fit`` does
#: unless told (its structure chosen by held-out error); "paper" is the paper's own: anisotropic, m = 8,
#: n = 3, one fall-off scaled by (1, s_g, s_b)
DEMO_FITS = {
    "default": dict(),
    "paper": dict(model="aniso", n_terms=3, n_directions=8, colour="shared"),
    "iso": dict(model="iso", n_terms=3),
    "dipole": dict(model="dipole"),
    "burley": dict(model="burley"),
}
#: the steps of the main job: each material, each fit, the relighting, the report and Figure 2
DEMO_STEPS = len(MATERIALS) + len(DEMO_FITS) + 3


def run_demo(
    out_dir,
    *,
    n_terms: int = 3,
    step: Callable[[str], None] | None = None,
    dataset=None,
    max_rounds: int = 3,
    overwrite: bool = False,
    reporter: Reporter | None = None,
) -> dict:
    """Run the main job and write its outputs under ``out_dir``.

    ``translucency demo`` is this function.  ``step(name)`` is told as each step begins; a ``reporter``
    (:class:`translucency.resources.run.Reporter`) shows the steps as one progress of
    :data:`DEMO_STEPS`.

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
        The planar fits of the default data set (``dataset`` overrides it), each with its α: the
        default (its structure chosen by held-out error), the paper's (anisotropic, m = 8, shared
        colour), iso (n = 3), dipole and Burley (:data:`DEMO_FITS`).
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

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as tmp:   # a folder of someone else's files: refused at once
    ...     _ = (Path(tmp) / "notes.txt").write_text("mine")
    ...     run_demo(tmp)   # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: out ...: exists and is not a translucency output folder; ...
    """
    # the terms of the sum of exponentials: 1 to 4, as in every fit (translucency.fit.check_fit_options)
    if isinstance(n_terms, bool) or not isinstance(n_terms, numbers.Integral) or not 1 <= n_terms <= 4:
        raise TranslucencyError(f"n_terms: must be a whole number between 1 and 4, got {n_terms!r}")
    if reporter is not None:  # the steps as one progress, then the job itself
        job = dict(n_terms=n_terms, dataset=dataset, max_rounds=max_rounds, overwrite=overwrite)
        return _with_progress(reporter, out_dir, step, job)
    out_dir = claim_folder(out_dir, overwrite=overwrite, inputs=[dataset])
    png, js, mpath = _baselines(out_dir, n_terms, step)
    # -- the embedded measurement: planar fits and Figure 1 -------------------------
    ds = open_dataset(dataset or default_dataset_path())
    embedded = dataset is None  # the default data come with their held-out truth and fine profiles
    truth = open_dataset(default_truth_path()) if embedded else None
    models, flagged = _demo_fits(ds, out_dir, max_rounds, step)
    _relight(ds, models, out_dir, embedded, step)
    if step:
        step("report")
    # -- Figure 2: the pig, acquired per vertex, fitted, rendered beside volpath ------------
    if step:
        step("figure 2")
    fig2, paper, fig2_structure = _figure2(out_dir)
    write_report(
        models,
        ds,
        out_dir / "report",
        flagged=flagged,
        truth=truth,
        fine=default_fine_profiles_path() if embedded else None,
        extra=_report_extras(fig2, paper, fig2_structure),
    )
    return {
        "figure": png,
        "summary": js,
        "model": mpath,
        "fits": out_dir / "fits",
        "pig": out_dir / "pig.zarr",
        "report": out_dir / "report" / "index.html",
    }


def _with_progress(reporter: Reporter, out_dir, step: Callable[[str], None] | None, job: dict) -> dict:
    """The main job with its steps shown by ``reporter`` as one progress of :data:`DEMO_STEPS`."""
    if not flip_available():  # Figure 2's numbers without FLIP: the job goes on and says so
        reporter.info(FLIP_SKIPPED)
    with reporter.progress("demo", DEMO_STEPS) as update:
        begun = itertools.count(1)

        def told(name: str) -> None:
            if step:
                step(name)
            update(completed=next(begun), item=name)

        return run_demo(out_dir, step=told, **job)


def _baselines(out_dir, n_terms: int, step: Callable[[str], None] | None):
    """Step 1: dipole, Burley and exponential fit per material; the figure, the numbers, the model file."""
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

    # the fits as one per-channel exponential model (C = 3, m = 1) of semi-infinite slabs
    mpath = save_model(
        fits_model(profiles),
        out_dir / "dipole_fits.model.zip",
        overwrite=True,
        meta={"materials": list(MATERIALS), "source": "3-term fits of the Jensen 2001 dipole"},
    )
    return png, js, mpath


def _demo_fits(ds, out_dir, max_rounds: int, step: Callable[[str], None] | None):
    """Step 2's planar fits (:data:`DEMO_FITS`), each saved under ``fits/``: the models and flagged points."""
    models, flagged = {}, {}
    for label, kw in DEMO_FITS.items():
        if step:
            step(f"fit {label}")
        fit = fit_planar(ds, max_rounds=max_rounds, **kw)
        save_model(
            fit.model, out_dir / "fits" / f"{label}.model.zip", overwrite=True, meta=fit.metadata(ds.path)
        )
        models[label], flagged[label] = fit.model, fit.flagged
    return models, flagged


def _relight(ds, models: dict, out_dir, embedded: bool, step: Callable[[str], None] | None) -> None:
    """Relighting: a stripe of light, models against photon transport (``report/relight.png``, ``.json``)."""
    if step:
        step("relighting")
    relit = relight_check(
        ds,
        {k: models[k] for k in ("default", "iso", "dipole")},
        out_dir / "report" / "relight.png",
        volume=demo_volume() if embedded else None,
    )
    write_json(out_dir / "report" / "relight.json", relit)


def _figure2(out_dir):
    """Figure 2 made under ``report/``: its numbers, those of the paper's choice, and the structure chosen."""
    fig2 = run_figure2(
        out_dir / "report",
        out_dir / "pig.zarr",
        out_dir / "fits" / "pig_iso.model.zip",
        overwrite=True,
        paper_dir=out_dir / "report" / "paper",
    )
    paper = json.loads((out_dir / "report" / "paper" / "figure2_paper.json").read_text())
    pig_fit = read_header(out_dir / "fits" / "pig_iso.model.zip")["meta"]["fit"]
    fig2_structure = pig_fit["structure"]["chosen"]["label"] if pig_fit.get("structure") else "as given"
    return fig2, paper, fig2_structure


def _report_extras(fig2: dict, paper: dict, fig2_structure: str) -> list:
    """The report's extra figures with their captions: the relighting and Figure 2 (default, paper's)."""
    return [
        (
            "relight.png",
            "Relighting: the sample under a 2 mm stripe of light, photon transport (reference) against "
            "the fitted models (superposition of R_d over the incident cells); green channel.",
        ),
        (
            "figure2.png",
            "Figure 2: the procedural alabaster pig (generated marble filling, index-matched), "
            "path-traced by Mitsuba volpath (left) and rendered from the per-vertex model fitted to its "
            "virtual acquisition as fit does by default (middle: its structure chosen by held-out "
            f"error, {fig2_structure}; each point's profile with the through-body table, as render "
            f"draws it); {_flip(fig2)}"
            f"relative RMSE {fig2['rel_rmse']:.2f} over the object; "
            "by region (relative RMSE, pixels): "
            + ", ".join(
                f"{k} {v['rel_rmse']:.2f} ({v['pixels']})" for k, v in fig2["regions"].items() if k != "all"
            )
            + ".",
        ),
        (
            "paper/figure2_paper.png",
            "Figure 2 with the paper's choice: the isotropic model with n = 3 and the colour scale "
            "(1, s_g, s_b), fitted to the same data and rendered from each point's radial profile alone "
            "(render --paper: without the through-body table, each pair's profile corrected by its "
            "measured energy per cell of normal cosine × distance); "
            f"{_flip(paper)}"
            f"relative RMSE {paper['rel_rmse']:.3f} (the default above: {fig2['rel_rmse']:.3f}).",
        ),
    ]


def _flip(numbers: dict) -> str:
    """The report's words for a comparison's FLIP: its mean over the object, or that it was not measured.

    Examples
    --------
    >>> _flip({"flip_mean_object": 0.1234}), _flip({})
    ('FLIP 0.123, ', 'FLIP not measured (the flip extra), ')
    """
    flip = numbers.get("flip_mean_object")
    return "FLIP not measured (the flip extra), " if flip is None else f"FLIP {flip:.3f}, "
