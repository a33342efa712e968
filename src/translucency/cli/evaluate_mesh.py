"""The mesh branch of ``translucency evaluate``: per-vertex models on their mesh data set, or held out
against an independent acquisition of the same object (``--truth``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rich.table import Table

from .. import resources
from .._validate import TranslucencyError
from ..io.dataset import dataset_identity
from ..io.mesh_dataset import is_mesh_dataset, open_mesh_dataset
from ..io.model_file import load_model, read_header
from ..io.outputs import claim_output
from ._common import warn
from ._run import Run

#: what ``evaluate`` takes, for the lines that refuse a mismatch
ACCEPTS = (
    "evaluate takes a planar model with a planar data set (acquire planar, import), or a per-vertex "
    "model with a mesh data set (acquire mesh)"
)


def evaluate_mesh(
    run: Run,
    model: Path,
    data: Path,
    *,
    report: Path,
    json_out: Path | None,
    to_stdout: bool,
    compare: list[Path],
    points: str | None,
    truth: Path | None,
    overwrite: bool,
    scheduler: str,
) -> None:
    """``evaluate MODEL MESH.zarr [--truth OTHER.zarr]``: every check before any output, then the report."""
    # heavy: the stages (SciPy, trimesh, Matplotlib) load only when an evaluation runs, not for --help
    from ..evaluate.labels import model_label, noise_label
    from ..evaluate.mesh_errors import check_model_points, check_same_points
    from ..evaluate.mesh_report import write_mesh_report

    if points is not None:
        raise TranslucencyError("--points: profiles are drawn for planar data sets; a mesh report has none")
    if scheduler not in (None, "threads"):
        warn(f"--scheduler {scheduler}: a mesh data set is evaluated in this process")
    run.timer = "evaluate mesh"  # its own time terms and calibration (resources.timing.TIME_TERMS)
    ds = open_mesh_dataset(data)
    other = None
    if truth is not None:
        if not is_mesh_dataset(truth):
            raise TranslucencyError(f"--truth {truth}: not a mesh data set, and {data} is one; {ACCEPTS}")
        other = open_mesh_dataset(truth)
        check_same_points(ds, other)
        if dataset_identity(other.header) != dataset_identity(ds.header):
            warn(
                f"--truth {truth} measured another object or filling than {data}; "
                "the errors compare two materials"
            )
    models, flagged, exclusion = {}, {}, {}
    for path in [model, *(compare or [])]:
        m = load_model(path)
        if m.geometry != "mesh":
            raise TranslucencyError(f"{path}: a planar model, and {data} is a mesh data set; {ACCEPTS}")
        check_model_points(m, ds)
        if other is not None:
            check_model_points(m, other)
        meta = read_header(path).get("meta", {})
        meta = meta if isinstance(meta, dict) else {}
        name = model_label(m)
        name = name if name not in models else f"{name} ({path.name})"
        models[name] = m
        exclusion[name] = (meta.get("fit") or {}).get("exclusion_mm")  # evaluate where the fit looked
        mask = np.zeros(m.n_points, bool)
        mask[np.asarray(meta.get("flagged_points", []), dtype=int)] = True
        flagged[name] = mask
        fitted_to = meta.get("acquisition")
        if isinstance(fitted_to, dict) and dataset_identity(fitted_to) != dataset_identity(ds.header):
            warn(
                f"{path} was fitted to another object or filling than {data}; "
                "its errors compare two materials"
            )
    V, F = len(ds["vertices"]), int(ds.group["faces"].shape[0])
    d = 2 if truth is not None else 1
    run.check(
        resources.memory.mesh_evaluation(points=ds.n_points, vertices=V, faces=F, models=len(models)), report
    )
    inputs = [model, data, *(compare or []), truth]
    if json_out is not None:
        claim_output(json_out, "json summary", overwrite=overwrite, inputs=inputs, option="--json-out")
    run.claim_folder(report, overwrite=overwrite, inputs=inputs, option="--report")
    timing = run.time(
        resources.timing.mesh_evaluation_units(points=ds.n_points, vertices=V, models=len(models), datasets=d)
    )
    run.info(
        f"{len(models)} per-vertex model(s) on {ds.n_points} points x {V:,} vertices; time {timing.text()}"
    )
    with run.work():
        summary = write_mesh_report(models, ds, report, truth=other, flagged=flagged, exclusion=exclusion)
    title = (
        f"relative L2 error against the truth {truth}"
        if truth
        else f"relative L2 error on {data} (in-sample)"
    )
    table = Table(title=title)
    columns = ["model", "all", "near <1 mm", "mid 1-4 mm", "far >4 mm"]
    for col in columns + (["beyond noise (all)", "in-sample all"] if truth else []):
        table.add_column(col)
    for name, s in summary["models"].items():
        cells = [f"{100 * s[k]:.2f} %" for k in ("rel_l2", "rel_l2_near", "rel_l2_mid", "rel_l2_far")]
        if truth:
            cells += [f"{100 * s['beyond_noise']['all']:.2f} %", f"{100 * s['in_sample']['rel_l2']:.2f} %"]
        table.add_row(name, *cells)
    nf = summary["noise_floor"]
    table.add_row(
        f"[dim]{noise_label(truth is not None)}[/]",
        *(f"[dim]{100 * nf[k]:.2f} %[/]" for k in ("all", "near", "mid", "far")),
    )
    run.finish_report(to_stdout, {"command": "evaluate", **summary}, report, table, json_out)
