"""``translucency evaluate``: a model's relative L2 errors on its data set (overall, per distance band,
energy-weighted) or against an independent truth, error maps, profiles and the HTML report
(:func:`translucency.workflow.evaluating.evaluate_report`, planar or mesh); the table printed here."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from ._common import (
    PANEL_COMPARISON,
    PANEL_OUTPUT,
    PANEL_TRANSPORT,
    finish,
    json_option,
    max_memory_option,
    overwrite_option,
    quiet_option,
    scheduler_option,
    user_errors,
)
from ._run import RichReporter

_TRUTH = typer.Option(
    None,
    "--truth",
    help="An independent acquisition of the same incident points (another seed, more photons; on a "
    "mesh: the same mesh and --points): errors against it, with the in-sample errors beside.",
    rich_help_panel=PANEL_COMPARISON,
)
_PAPER = typer.Option(
    False,
    "--paper",
    help="Evaluate a per-vertex model as the paper's model (each point's radial profile alone), not as "
    "render draws it (with the model's through-body table).",
    rich_help_panel=PANEL_TRANSPORT,
)


_REPORT = typer.Option(
    None,
    "--report",
    help="Directory for the figures and index.html (default: beside the model, MODEL.report/ — "
    "iso.model.zip gives iso.report/).",
)
_JSON_OUT = typer.Option(
    None,
    "--json-out",
    help="Also write the summary (the object --json prints: rel_l2, rel_l2_near/mid/far, ...) to this file.",
    rich_help_panel=PANEL_OUTPUT,
)
_COMPARE = typer.Option(
    None,
    "--compare",
    help="Other model files of the same data (repeatable).",
    rich_help_panel=PANEL_COMPARISON,
)
_PROFILES = typer.Option(
    None,
    "--profiles",
    help="The incident points whose profiles are drawn, e.g. 0,17,40 (planar data sets).",
    rich_help_panel=PANEL_OUTPUT,
)


@user_errors
def evaluate(
    model: Path = typer.Argument(..., help="The model file to evaluate (.model.zip)."),
    data: Path = typer.Argument(
        ...,
        help="The data set it was fitted to (.zarr directory): a planar data set for a planar model, a mesh "
        "data set for a per-vertex model.",
    ),
    report: Path = _REPORT,
    json_out: Path = _JSON_OUT,
    compare: list[Path] = _COMPARE,
    profiles: str = _PROFILES,
    truth: Path = _TRUTH,
    paper: bool = _PAPER,
    overwrite: bool = overwrite_option(),
    scheduler: str = scheduler_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Relative L2 errors (overall, per distance band, energy-weighted), error maps, profiles, HTML report: a
    planar model on its planar data set, or a per-vertex model on its mesh data set."""
    from ..workflow.evaluating import evaluate_report  # heavy: Dask and Matplotlib load only to evaluate

    evaluation = evaluate_report(
        model, data, report, compare=compare or (), profiles=profiles, truth=truth, json_out=json_out,
        overwrite=overwrite, scheduler=scheduler, max_memory=max_memory, reporter=RichReporter(quiet),
        paper=paper,
    )  # fmt: skip
    lines = [_table(evaluation, data, truth), f"report: {evaluation.report / 'index.html'}"]
    finish(as_json, quiet, evaluation.summary, lines)


def _table(evaluation, data: Path, truth: Path | None) -> Table:
    """The errors per model (and the noise floor) as a table: planar models with their total reflectance,
    per-vertex models held out with their error beyond the noise; its title says what the errors are
    measured against, its caption what the bands and the noise row mean and which figure to trust."""
    from ..workflow.evaluating import table_caption  # the report's words, loaded with the evaluation

    summary, mesh, held_out = evaluation.summary, evaluation.geometry == "mesh", truth is not None
    where = "vertices" if mesh else "pixels"
    table = Table(title=_title(data, truth, where), caption=table_caption(held_out, where))
    columns = ["model", "all", "near <1 mm", "mid 1-4 mm", "far >4 mm\nfrom the light"]
    columns += [] if mesh else ["total refl."]
    if held_out:
        columns += (["beyond noise (all)"] if mesh else []) + ["in-sample all"]
    for col in columns:
        table.add_column(col)
    for name, s in summary["models"].items():
        cells = [f"{100 * s[k]:.2f} %" for k in ("rel_l2", "rel_l2_near", "rel_l2_mid", "rel_l2_far")]
        if not mesh:
            cells.append(f"{100 * s['energy_error']['total']:.2f} %")
        if held_out and mesh:
            cells.append(f"{100 * s['beyond_noise']['all']:.2f} %")
        if held_out:
            cells.append(f"{100 * s['in_sample']['rel_l2']:.2f} %")
        table.add_row(name, *cells)
    nf = summary["noise_floor"]
    table.add_row(
        f"[dim]{evaluation.noise} (the floor)[/]",
        *(f"[dim]{100 * nf[k]:.2f} %[/]" for k in ("all", "near", "mid", "far")),
    )
    return table


def _title(data: Path, truth: Path | None, where: str) -> str:
    """What the errors are measured against, in words."""
    error = "relative L2 error ||model - R_d|| / ||R_d||"
    if truth is not None:
        return f"{error} against the truth {truth}, held out: an independent acquisition the model never saw"
    return f"{error} on {data}, in-sample: the very {where} the model was fitted to"
