"""Evaluation as functions: a fitted model's relative L2 errors on its data set or on an independent truth
(:func:`evaluate_model`, in memory), and ``translucency evaluate``'s report of model files
(:func:`evaluate_report`: the errors, error maps, profiles and ``index.html``)."""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import resources
from .._validate import TranslucencyError, check_option
from ..evaluate.errors import PlanarErrors, planar_errors
from ..evaluate.labels import (
    model_label,
    noise_label,
    table_caption,  # noqa: F401 — the command line's words under its table
)
from ..evaluate.mesh_errors import MeshErrors, check_model_points, check_same_points, mesh_errors
from ..io.atomic import write_json
from ..io.dataset import PlanarDataset, dataset_identity
from ..io.dataset import open_dataset as open_planar
from ..io.inputs import DATA_SETS, expect_input, what_is
from ..io.mesh_dataset import MeshDataset, is_mesh_dataset, open_mesh_dataset
from ..io.model_file import load_model, read_header
from ..io.outputs import claim_output
from ..io.records import jsonable
from ..resources.run import Reporter, Run
from ._arguments import as_path, model_and_record, whole_number
from .datasets import open_dataset

__all__ = ["Evaluation", "evaluate_model", "evaluate_report"]


def evaluate_model(
    model,
    dataset,
    *,
    truth=None,
    flagged=None,
    exclusion_mm: float | None = None,
    scheduler: str | None = "threads",
    paper: bool = False,
) -> PlanarErrors | MeshErrors:
    """Relative L2 errors of a fitted model on its data set, or on an independent truth.

    A planar model on a planar data set: :func:`translucency.evaluate.errors.planar_errors`; a per-vertex
    model on a mesh data set: :func:`translucency.evaluate.mesh_errors.mesh_errors` (the numbers of
    ``translucency evaluate``; the reports: :func:`translucency.evaluate.report.write_report`,
    :func:`translucency.evaluate.mesh_report.write_mesh_report`).

    Parameters
    ----------
    model : FitResult, ReflectanceModel or path
        The fit (its flagged points and exclusion radius are used), a model, or a model file (the fit's
        record in it is used).
    dataset : PlanarDataset, MeshDataset or path
        The data set the model was fitted to.
    truth : PlanarDataset, MeshDataset or path, optional
        An independent acquisition of the same incident points (another photon seed, usually more
        photons; on a mesh the same mesh and incident vertices): the errors are then held out, against
        the material rather than the fitted noise.
    flagged : array of bool, optional
        Points to leave out (default: those the fit flagged).
    exclusion_mm : float, optional
        Pairs closer than this are left out (default: the fit's, else one pixel / half the mean edge).
    scheduler : str, optional
        Where the chunks of a planar evaluation run; the errors are the same.
    paper : bool
        A per-vertex model is evaluated as ``render`` draws it, with its through-body table
        (:mod:`translucency.model.through`); ``paper`` evaluates the paper's model alone.

    Returns
    -------
    PlanarErrors or MeshErrors
        ``rel_l2`` (overall), ``bands`` (near < 1 mm, mid 1–4 mm, far > 4 mm), ``noise`` (the
        reference's noise floor), ``energy``, ``beyond_noise`` and the errors per point (and per pixel
        or per vertex).

    Raises
    ------
    TranslucencyError
        A planar model with a mesh data set or the reverse, a model of other incident points, or a
        truth of other incident points.

    Examples
    --------
    The embedded scan fitted quickly (two terms, one round) and its errors held out against the
    embedded truth (the same points, independent photons):

    >>> import translucency as tl
    >>> data = tl.data.default_dataset()
    >>> fitting = tl.fit_model(data, "iso", n_terms=2, max_rounds=1)
    >>> errors = tl.evaluate_model(fitting.result, data, truth=tl.data.default_truth())
    >>> sorted(errors.bands), bool(0 < errors.noise["all"] < errors.rel_l2 < 0.5)
    (['far', 'mid', 'near'], True)

    ``tl.fit_model(data)`` (the structure chosen, three rounds) comes closer, in about a minute.
    """
    fitted, record = model_and_record("model", model)
    data = open_dataset(dataset) if isinstance(dataset, (str, os.PathLike)) else dataset
    if not isinstance(data, (PlanarDataset, MeshDataset)):
        raise TranslucencyError(f"dataset: expected a data set or its path, got {type(data).__name__}")
    geometry = getattr(fitted, "geometry", "planar")
    wanted = "mesh" if isinstance(data, MeshDataset) else "planar"
    if geometry != wanted:
        raise TranslucencyError(
            f"model: a {'per-vertex' if geometry == 'mesh' else 'planar'} model and a {wanted} data set; "
            "evaluate takes a planar model with a planar data set, or a per-vertex model with a mesh data set"
        )
    reference = data
    if truth is not None:
        reference = open_dataset(truth) if isinstance(truth, (str, os.PathLike)) else truth
        if not isinstance(reference, type(data)):
            raise TranslucencyError(
                f"truth: expected a {wanted} data set (as dataset) or its path, "
                f"got {type(reference).__name__}"
            )
        if isinstance(data, MeshDataset):
            check_same_points(data, reference)
        if dataset_identity(reference.header) != dataset_identity(data.header):
            warnings.warn(
                f"truth {reference.path}: measured another sample than {data.path}; "
                "the errors compare two materials",
                stacklevel=2,
            )
    if flagged is None:
        flagged = np.zeros(fitted.n_points, bool)
        flagged[np.asarray(record.get("flagged_points", []), dtype=int)] = True
    if exclusion_mm is None:
        exclusion_mm = (record.get("fit") or {}).get("exclusion_mm")
    check_option("exclusion_mm", exclusion_mm, lo=0)
    if isinstance(data, MeshDataset):
        through = False if paper else None
        return mesh_errors(fitted, reference, flagged=flagged, exclusion_mm=exclusion_mm, through=through)
    return planar_errors(fitted, reference, flagged=flagged, exclusion_mm=exclusion_mm, scheduler=scheduler)


#: what :func:`evaluate_report` takes, for the lines that refuse a mismatch
ACCEPTS = (
    "evaluate takes a planar model with a planar data set (acquire planar, import), or a per-vertex "
    "model with a mesh data set (acquire mesh)"
)


@dataclass
class Evaluation:
    """What :func:`evaluate_report` made: the report's folder and the summary of ``evaluate --json``.

    Examples
    --------
    Its fields (:func:`evaluate_report`'s example makes one):

    >>> import dataclasses
    >>> import translucency as tl
    >>> [field.name for field in dataclasses.fields(tl.Evaluation)]
    ['summary', 'report', 'geometry', 'noise']
    """

    summary: dict  # rel_l2, rel_l2_near/mid/far per model, noise_floor, estimates, seconds, report
    report: Path  # the folder with index.html, the figures and report.json
    geometry: str  # "planar" or "mesh": which data set the models were evaluated on
    noise: str  # what the noise floor is (the truth's noise, or the data's own), for a table's last row


def evaluate_report(
    model,
    dataset,
    report=None,
    *,
    compare=(),
    profiles=None,
    truth=None,
    json_out=None,
    overwrite: bool = False,
    scheduler: str | None = "threads",
    max_memory: str | int | None = None,
    reporter: Reporter | None = None,
    paper: bool = False,
) -> Evaluation:
    """Evaluate model files on their data set and write the report: relative L2 errors (overall, per
    distance band, energy-weighted), error maps, profiles and ``index.html``.

    ``translucency evaluate MODEL DATA`` is this function: a planar model on its planar data set
    (:func:`translucency.evaluate.report.write_report`), or a per-vertex model on its mesh data set
    (:func:`translucency.evaluate.mesh_report.write_mesh_report`); every check before any output, the
    memory and time estimated before the work.  The errors alone, in memory: :func:`evaluate_model`.

    Parameters
    ----------
    model : str or Path
        The model file to evaluate (``.model.zip``).
    dataset : str or Path
        The data set it was fitted to: planar for a planar model, a mesh data set for a per-vertex one.
    report : str or Path, optional
        Folder for the figures and ``index.html`` (default: beside the model, ``iso.model.zip`` gives
        ``iso.report/``).
    compare : sequence of paths
        Other model files of the same data, evaluated beside ``model``.
    profiles : str or sequence of int, optional
        The incident points whose profiles are drawn (``"0,17,40"`` or ``[0, 17, 40]``; planar data sets
        only; ``points`` still works for one release, with a DeprecationWarning).
    truth : str or Path, optional
        An independent acquisition of the same incident points (another seed, more photons; on a mesh
        the same mesh and points): the errors against it, with the in-sample errors beside.
    json_out : str or Path, optional
        Also write the summary (the returned ``.summary``) to this file.
    overwrite : bool
        Replace an earlier report (and ``json_out``) of translucency (never anything else).
    scheduler : str, optional
        Where a planar evaluation's chunks run (``"threads"``, ``"local:N"``, ``"tcp://HOST:PORT"``); the
        errors are the same.  A mesh data set is evaluated in this process.
    max_memory : str or int, optional
        Most memory the evaluation may use; a larger estimate is refused before any work.
    reporter : Reporter, optional
        Hears the run's information lines (default: silent).
    paper : bool
        Per-vertex models are evaluated as ``render`` draws them, with their through-body table; ``paper``
        evaluates the paper's model alone (each point's radial profile).

    Returns
    -------
    Evaluation
        ``.summary`` (``translucency evaluate --json``), ``.report``, ``.geometry``, ``.noise``.

    Raises
    ------
    TranslucencyError
        A path of another kind (model and data swapped, a data set as ``compare``), a planar model with a
        mesh data set or the reverse, points that are not the data set's, an output not translucency's.

    Examples
    --------
    A small marble slab scanned twice (the data, and an independent truth with more photons), fitted and
    reported (seconds, most of them the report's figures):

    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> folder = Path(tempfile.mkdtemp())
    >>> slab = tl.make_sample("marble", (8.0, 8.0, 3.0), 0.5)
    >>> scan = dict(grid=3, span=2.0, window=3.0, pitch=0.5)
    >>> data = tl.acquire_planar(slab, folder / "m.zarr", photons=500, **scan)
    >>> truth = tl.acquire_planar(slab, folder / "truth.zarr", photons=2000, seed=2, **scan)
    >>> fit = tl.fit_model(folder / "m.zarr", "iso", folder / "iso.model.zip", n_terms=2)
    >>> ev = tl.evaluate_report(folder / "iso.model.zip", folder / "m.zarr", truth=folder / "truth.zarr")
    >>> ev.geometry, ev.report.name, (ev.report / "index.html").is_file()
    ('planar', 'iso.report', True)
    >>> bool(ev.summary["rel_l2"] >= ev.summary["noise_floor"]["all"])
    True

    The embedded scan and its truth (:func:`translucency.data.default_dataset_path`,
    :func:`~translucency.data.default_truth_path`) are reported the same way, in about a minute.
    """
    from ..cluster import parse_scheduler  # heavy: Dask loads only when an evaluation runs

    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    model, dataset = as_path("model", model), as_path("dataset", dataset)
    compare = [as_path("compare", p) for p in compare or ()]
    truth = None if truth is None else as_path("truth", truth)
    json_out = None if json_out is None else as_path("json_out", json_out)
    _check_inputs(model, dataset, compare, truth)
    run = Run("evaluate", max_memory=max_memory, reporter=reporter)
    report = report_beside(model) if report is None else as_path("report", report)
    paths = dict(model=model, dataset=dataset, compare=compare, truth=truth, report=report)
    outputs = dict(json_out=json_out, overwrite=overwrite)
    if is_mesh_dataset(dataset):  # per-vertex models on a mesh data set
        summary = _mesh_report(run, paths, outputs, points=profiles, scheduler=scheduler, paper=paper)
        geometry = "mesh"
    else:
        summary = _planar_report(run, paths, outputs, points=profiles, scheduler=scheduler)
        geometry = "planar"
    summary = run.summary({"command": "evaluate", "report": report / "index.html", **summary})
    if json_out is not None:  # the object the command's --json prints
        write_json(json_out, jsonable(summary))
    return Evaluation(summary, report, geometry, noise_label(truth is not None))


def report_beside(model: Path) -> Path:
    """The default report folder of ``model``: beside it, its name with ``.report`` for ``.model.zip``.

    Examples
    --------
    >>> report_beside(Path("fits/iso.model.zip"))
    PosixPath('fits/iso.report')
    """
    name = model.name.removesuffix(".zip").removesuffix(".model") or model.name
    return model.with_name(name + ".report")


def _check_inputs(model: Path, dataset: Path, compare: list, truth: Path | None) -> None:
    """Each path of the kind it should be (model files, data sets), or one line naming it."""
    if what_is(model) in DATA_SETS and what_is(dataset) == "model file":
        raise TranslucencyError(
            f"{model}: is a data set and {dataset} a model file: swapped? evaluate takes MODEL DATA "
            f"(translucency evaluate {dataset} {model})"
        )
    for path, option in [(model, None), *((p, "compare") for p in compare)]:
        expect_input(path, ("model file",), option)
    expect_input(dataset, DATA_SETS)
    expect_input(truth, DATA_SETS, "truth")


def _parse_points(points) -> list[int] | None:
    """The profiles' incident points: ``"0,17,40"`` or a sequence of whole numbers."""
    if points is None:
        return None
    if isinstance(points, str):
        try:
            return [int(v) for v in points.split(",") if v.strip()]
        except ValueError:
            raise TranslucencyError(f"profiles: expected comma-separated integers, got {points!r}") from None
    if isinstance(points, (int, np.integer)):
        points = [points]
    return [whole_number("profiles", p, lo=0) for p in points]


def _read_models(paths: list[Path], geometry: str, data: Path, check=None):
    """{label: model}, {label: flagged}, {label: exclusion}, {path: meta} of model files of ``geometry``
    (``check(model)``: further checks of each)."""
    models, flagged, exclusion, metas = {}, {}, {}, {}
    for path in paths:
        m = load_model(path)
        if m.geometry != geometry:
            raise TranslucencyError(
                f"{path}: a per-vertex model, and {data} is not a mesh data set; {ACCEPTS}"
                if geometry == "planar"
                else f"{path}: a planar model, and {data} is a mesh data set; {ACCEPTS}"
            )
        if check is not None:
            check(m)
        meta = read_header(path).get("meta", {})
        metas[path] = meta = meta if isinstance(meta, dict) else {}
        name = model_label(m)
        name = name if name not in models else f"{name} ({path.name})"
        models[name] = m
        exclusion[name] = (meta.get("fit") or {}).get("exclusion_mm")  # evaluate where the fit looked
        mask = np.zeros(m.n_points, bool)
        mask[np.asarray(meta.get("flagged_points", []), dtype=int)] = True
        flagged[name] = mask
    return models, flagged, exclusion, metas


def _claim(run: Run, paths: dict, outputs: dict) -> None:
    """The outputs, claimed before any work: the summary file (``json_out``), the report folder."""
    inputs = [paths["model"], paths["dataset"], *paths["compare"], paths["truth"]]
    overwrite = outputs["overwrite"]
    if outputs["json_out"] is not None:
        claim_output(
            outputs["json_out"], "json summary", overwrite=overwrite, inputs=inputs, option="json_out"
        )
    run.claim_folder(paths["report"], overwrite=overwrite, inputs=inputs, option="report")


def _planar_report(run: Run, paths: dict, outputs: dict, *, points, scheduler) -> dict:
    """A planar data set's evaluation under ``run``: checks, estimates, claims, then the report."""
    from ..evaluate.report import write_report  # heavy: Dask and Matplotlib load only to evaluate

    data, truth, report = paths["dataset"], paths["truth"], paths["report"]
    if truth is not None and is_mesh_dataset(truth):
        raise TranslucencyError(f"truth {truth}: a mesh data set, and {data} is planar; {ACCEPTS}")
    models, flagged, exclusion, metas = _read_models([paths["model"], *paths["compare"]], "planar", data)
    picks = _parse_points(points)
    ds = open_planar(data)
    for p in picks or []:
        if not 0 <= p < ds.n_points:
            raise TranslucencyError(
                f"profiles: {p} is not an incident point of {data} (0..{ds.n_points - 1})"
            )
    H, W = ds.window
    params = [int(np.prod(m.param_shape)) for m in models.values()]
    d = 2 if truth is not None else 1
    run.check(
        resources.memory.evaluation(points=ds.n_points, pixels=H * W, params=params, datasets=d), report
    )
    _warn_other_sample(metas, ds, truth)
    _claim(run, paths, outputs)
    units = resources.timing.evaluation_units(points=ds.n_points, pixels=H * W, params=params, datasets=d)
    timing = run.time(units)
    run.info(f"{len(models)} model(s) on {ds.n_points} points x {H} x {W} pixels; time {timing.text()}")
    with run.work():
        return write_report(
            models,
            ds,
            report,
            points=picks,
            flagged=flagged,
            truth=truth,
            exclusion=exclusion,
            scheduler=scheduler,
        )


def _mesh_report(run: Run, paths: dict, outputs: dict, *, points, scheduler, paper: bool = False) -> dict:
    """A mesh data set's evaluation under ``run`` (or held out against an independent acquisition of the
    same object): every check before any output, then the report."""
    # heavy: the stages (SciPy, trimesh, Matplotlib) load only when an evaluation runs
    from ..evaluate.mesh_report import write_mesh_report

    data, truth, report = paths["dataset"], paths["truth"], paths["report"]
    if points is not None:
        raise TranslucencyError("profiles: drawn for planar data sets; a mesh report has none")
    if scheduler not in (None, "threads"):
        warnings.warn(f"scheduler {scheduler}: a mesh data set is evaluated in this process", stacklevel=3)
    run.timer = "evaluate mesh"  # its own time terms and calibration (resources.timing.TIME_TERMS)
    ds = open_mesh_dataset(data)
    other = _mesh_truth(ds, data, truth)

    def same_points(m) -> None:
        check_model_points(m, ds)
        if other is not None:
            check_model_points(m, other)

    models, flagged, exclusion, metas = _read_models(
        [paths["model"], *paths["compare"]], "mesh", data, same_points
    )
    for path, meta in metas.items():
        fitted_to = meta.get("acquisition")
        if isinstance(fitted_to, dict) and dataset_identity(fitted_to) != dataset_identity(ds.header):
            warnings.warn(
                f"{path} was fitted to another object or filling than {data}; "
                "its errors compare two materials",
                stacklevel=3,
            )
    V, F = len(ds["vertices"]), int(ds.group["faces"].shape[0])
    d = 2 if truth is not None else 1
    run.check(
        resources.memory.mesh_evaluation(points=ds.n_points, vertices=V, faces=F, models=len(models)), report
    )
    _claim(run, paths, outputs)
    timing = run.time(
        resources.timing.mesh_evaluation_units(points=ds.n_points, vertices=V, models=len(models), datasets=d)
    )
    run.info(
        f"{len(models)} per-vertex model(s) on {ds.n_points} points x {V:,} vertices; time {timing.text()}"
    )
    with run.work():
        through = False if paper else None
        return write_mesh_report(
            models, ds, report, truth=other, flagged=flagged, exclusion=exclusion, through=through
        )


def _mesh_truth(ds: MeshDataset, data: Path, truth: Path | None) -> MeshDataset | None:
    """The mesh truth, checked to hold the same points (a warning if it measured another object)."""
    if truth is None:
        return None
    if not is_mesh_dataset(truth):
        raise TranslucencyError(f"truth {truth}: not a mesh data set, and {data} is one; {ACCEPTS}")
    other = open_mesh_dataset(truth)
    check_same_points(ds, other)
    if dataset_identity(other.header) != dataset_identity(ds.header):
        warnings.warn(
            f"truth {truth} measured another object or filling than {data}; the errors compare two materials",
            stacklevel=4,
        )
    return other


def _identity_of_model(meta: dict):
    """The identity of the data set a model was fitted to: recorded, or read from its acquisition header
    (mesh fits), or from the data set at the recorded path if it is still there (older model files)."""
    if isinstance(meta.get("dataset_identity"), dict):
        return meta["dataset_identity"]
    if isinstance(meta.get("acquisition"), dict):
        return dataset_identity(meta["acquisition"])
    recorded = meta.get("dataset")
    if isinstance(recorded, str) and recorded and Path(recorded).is_dir():
        try:
            opened = open_mesh_dataset(recorded) if is_mesh_dataset(recorded) else open_planar(recorded)
        except TranslucencyError:
            return None
        return dataset_identity(opened.header)
    return None


def _warn_other_sample(metas: dict, ds, truth) -> None:
    """A warning for a model fitted to data of another sample than ``ds`` (and for a truth of another
    sample): the errors would compare two materials."""
    own = dataset_identity(ds.header)
    for path, meta in metas.items():
        theirs = _identity_of_model(meta)
        if theirs is not None and theirs != own:
            warnings.warn(
                f"{path} was fitted to data of another sample than {ds.path} "
                f"(fitted to {meta.get('dataset', '?')}); its errors compare two materials",
                stacklevel=4,
            )
    if truth is not None:
        other = dataset_identity(open_planar(truth).header)
        if other != own:
            warnings.warn(
                f"truth {truth} measured another sample than {ds.path} (a generated sample is set by its "
                "sample seed, by default the photons' seed); the errors compare two materials",
                stacklevel=4,
            )
