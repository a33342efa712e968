"""``translucency evaluate``: a model's relative L2 errors on its data set (overall, per distance band,
energy-weighted) or against an independent truth, error maps, profiles and the HTML report; a mesh data
set goes to :mod:`.evaluate_mesh`."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer
from rich.table import Table

from .. import resources
from .._validate import TranslucencyError
from ..io.dataset import dataset_identity, open_dataset
from ..io.inputs import DATA_SETS, expect_input, what_is
from ..io.mesh_dataset import is_mesh_dataset, open_mesh_dataset
from ..io.model_file import load_model, read_header
from ..io.outputs import claim_output
from ._common import (
    json_option,
    max_memory_option,
    overwrite_option,
    quiet_option,
    scheduler_option,
    user_errors,
    warn,
)
from ._run import Run
from .evaluate_mesh import ACCEPTS, evaluate_mesh


@user_errors
def evaluate(
    model: Path = typer.Argument(..., help="The model file to evaluate (.model.zip)."),
    data: Path = typer.Argument(
        ...,
        help="The data set it was fitted to (.zarr directory): a planar data set for a planar model, a mesh "
        "data set for a per-vertex model.",
    ),
    report: Path = typer.Option(
        None,
        "--report",
        help="Directory for the figures and index.html (default: beside the model, MODEL.report/ — "
        "iso.model.zip gives iso.report/).",
    ),
    as_json: bool = json_option(),
    json_out: Path = typer.Option(
        None,
        "--json-out",
        help="Also write the summary (the object --json prints: rel_l2, rel_l2_near/mid/far, ...) to this "
        "file. The former --json PATH still works, with a warning.",
    ),
    compare: list[Path] = typer.Option(
        None, "--compare", help="Other model files of the same data (repeatable)."
    ),
    points: str = typer.Option(None, "--points", help="Incident points for the profiles, e.g. '0,17,40'."),
    truth: Path = typer.Option(
        None,
        "--truth",
        help="An independent acquisition of the same incident points (another seed, more photons; on a "
        "mesh: the same mesh and --points): errors against it, with the in-sample errors beside.",
    ),
    overwrite: bool = overwrite_option(),
    scheduler: str = scheduler_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
):
    """Relative L2 errors (overall, per distance band, energy-weighted), error maps, profiles, HTML report: a
    planar model on its planar data set, or a per-vertex model on its mesh data set."""
    from ..cluster import parse_scheduler  # heavy: Dask and Matplotlib load only when an evaluation runs
    from ..evaluate.labels import noise_label
    from ..evaluate.report import model_label, write_report

    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work

    if what_is(model) in DATA_SETS and what_is(data) == "model file":
        raise TranslucencyError(
            f"{model}: is a data set and {data} a model file: swapped? evaluate takes MODEL DATA "
            f"(translucency evaluate {data} {model})"
        )
    for path, option in [(model, None), *((p, "--compare") for p in compare or [])]:
        expect_input(path, ("model file",), option)
    expect_input(data, DATA_SETS)
    expect_input(truth, DATA_SETS, "--truth")
    run = Run("evaluate", max_memory=max_memory, quiet=quiet)
    report = report_beside(model) if report is None else report
    if is_mesh_dataset(data):  # per-vertex models on a mesh data set
        evaluate_mesh(
            run,
            model,
            data,
            report=report,
            json_out=json_out,
            to_stdout=as_json,
            compare=compare,
            points=points,
            truth=truth,
            overwrite=overwrite,
            scheduler=scheduler,
        )
        return
    if truth is not None and is_mesh_dataset(truth):
        raise TranslucencyError(f"--truth {truth}: a mesh data set, and {data} is planar; {ACCEPTS}")
    models, flagged, exclusion, metas = {}, {}, {}, {}
    for path in [model, *(compare or [])]:
        m = load_model(path)
        if m.geometry != "planar":
            raise TranslucencyError(
                f"{path}: a per-vertex model, and {data} is not a mesh data set; {ACCEPTS}"
            )
        meta = read_header(path).get("meta", {})
        metas[path] = meta if isinstance(meta, dict) else {}
        fl = meta.get("flagged_points", [])
        name = model_label(m)
        name = name if name not in models else f"{name} ({path.name})"
        models[name] = m
        exclusion[name] = meta.get("fit", {}).get("exclusion_mm")  # evaluate where the fit looked
        mask = np.zeros(m.n_points, bool)
        mask[np.asarray(fl, dtype=int)] = True
        flagged[name] = mask
    try:
        picks = None if points is None else [int(v) for v in points.split(",") if v.strip()]
    except ValueError:
        raise TranslucencyError(f"--points: expected comma-separated integers, got {points!r}") from None
    ds = open_dataset(data)
    for p in picks or []:
        if not 0 <= p < ds.n_points:
            raise TranslucencyError(
                f"--points: {p} is not an incident point of {data} (0..{ds.n_points - 1})"
            )
    H, W = ds.window
    params = [int(np.prod(m.param_shape)) for m in models.values()]
    d = 2 if truth is not None else 1
    run.check(
        resources.memory.evaluation(points=ds.n_points, pixels=H * W, params=params, datasets=d), report
    )
    _warn_other_sample(metas, ds, truth)
    inputs = [model, data, *(compare or []), truth]
    if json_out is not None:
        claim_output(json_out, "json summary", overwrite=overwrite, inputs=inputs, option="--json-out")
    run.claim_folder(report, overwrite=overwrite, inputs=inputs, option="--report")
    units = resources.timing.evaluation_units(points=ds.n_points, pixels=H * W, params=params, datasets=d)
    timing = run.time(units)
    run.info(f"{len(models)} model(s) on {ds.n_points} points x {H} x {W} pixels; time {timing.text()}")
    with run.work():
        summary = write_report(
            models,
            ds,
            report,
            points=picks,
            flagged=flagged,
            truth=truth,
            exclusion=exclusion,
            scheduler=scheduler,
        )
    title = (
        f"relative L2 error against the truth {truth}"
        if truth
        else f"relative L2 error on {data} (in-sample)"
    )
    table = Table(title=title)
    columns = ["model", "all", "near <1 mm", "mid 1-4 mm", "far >4 mm", "total refl."]
    table_columns = columns + (["in-sample all"] if truth else [])
    for col in table_columns:
        table.add_column(col)
    for name, s in summary["models"].items():
        cells = [f"{100 * s[k]:.2f} %" for k in ("rel_l2", "rel_l2_near", "rel_l2_mid", "rel_l2_far")]
        cells.append(f"{100 * s['energy_error']['total']:.2f} %")
        if truth:
            cells.append(f"{100 * s['in_sample']['rel_l2']:.2f} %")
        table.add_row(name, *cells)
    nf = summary["noise_floor"]
    table.add_row(
        f"[dim]{noise_label(truth is not None)}[/]",
        *(f"[dim]{100 * nf[k]:.2f} %[/]" for k in ("all", "near", "mid", "far")),
    )
    run.finish_report(as_json, {"command": "evaluate", **summary}, report, table, json_out)


class EvaluateCommand(typer.core.TyperCommand):
    """``evaluate``'s command line: the former ``--json PATH`` is read as ``--json-out PATH`` and
    ``--json -`` as ``--json``, each with a one-line deprecation warning."""

    def parse_args(self, ctx, args):
        return super().parse_args(ctx, _former_json(self, list(args)))


def _former_json(command, args: list[str]) -> list[str]:
    """``args`` with the former forms of ``--json`` rewritten: ``--json -``, ``--json=PATH`` and
    ``--json PATH`` where PATH is a third positional word (the command takes two: MODEL DATA)."""
    flags = {"--help"} | {
        name for p in command.params if getattr(p, "is_flag", False) for name in (*p.opts, *p.secondary_opts)
    }
    arguments = sum(1 for p in command.params if p.param_type_name == "argument")
    positional, i = [], 0
    while i < len(args):  # the indices of the positional words (each option's value skipped)
        word = args[i]
        if word == "--":
            positional += range(i + 1, len(args))
            break
        if word.startswith("-") and word != "-":
            i += 1 if word in flags or "=" in word else 2
            continue
        positional.append(i)
        i += 1
    out, i = [], 0
    while i < len(args):
        word, after = args[i], args[i + 1] if i + 1 < len(args) else None
        if word.startswith("--json="):
            after, word = word.split("=", 1)[1], "--json"
            i -= 1  # the value was part of this word
        elif (
            word != "--json"
            or after is None
            or not (after == "-" or (i + 1 in positional and len(positional) > arguments))
        ):
            out.append(word)
            i += 1
            continue
        if after == "-":
            warn("--json - is deprecated; --json alone prints the summary on stdout")
            out.append("--json")
        else:
            warn("--json PATH is deprecated; use --json > PATH or --json-out PATH")
            out += ["--json-out", after]
        i += 2
    return out


def report_beside(model: Path) -> Path:
    """The default report folder of ``model``: beside it, its name with ``.report`` for ``.model.zip``."""
    name = model.name.removesuffix(".zip").removesuffix(".model") or model.name
    return model.with_name(name + ".report")


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
            opened = open_mesh_dataset(recorded) if is_mesh_dataset(recorded) else open_dataset(recorded)
        except TranslucencyError:
            return None
        return dataset_identity(opened.header)
    return None


def _warn_other_sample(metas: dict, ds, truth) -> None:
    """A warning line for a model fitted to data of another sample than ``ds`` (and for a truth of another
    sample): the errors would compare two materials."""
    own = dataset_identity(ds.header)
    for path, meta in metas.items():
        theirs = _identity_of_model(meta)
        if theirs is not None and theirs != own:
            warn(
                f"{path} was fitted to data of another sample than {ds.path} "
                f"(fitted to {meta.get('dataset', '?')}); its errors compare two materials"
            )
    if truth is not None:
        other = dataset_identity(open_dataset(truth).header)
        if other != own:
            warn(
                f"--truth {truth} measured another sample than {ds.path} (a generated "
                "sample is set by --sample-seed, default --seed); the errors compare two materials"
            )
