"""``translucency evaluate``: a model's relative L2 errors on its data set (overall, per distance band,
energy-weighted) or against an independent truth, error maps, profiles and the HTML report
(:func:`translucency.workflow.evaluating.evaluate_report`, planar or mesh); the table printed here."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from ._common import (
    finish,
    json_option,
    max_memory_option,
    overwrite_option,
    quiet_option,
    scheduler_option,
    user_errors,
    warn,
)
from ._run import RichReporter

_TRUTH = typer.Option(
    None,
    "--truth",
    help="An independent acquisition of the same incident points (another seed, more photons; on a "
    "mesh: the same mesh and --points): errors against it, with the in-sample errors beside.",
)
_PAPER = typer.Option(
    False,
    "--paper",
    help="Evaluate a per-vertex model as the paper's model (each point's radial profile alone), not as "
    "render draws it (with the model's through-body table).",
)


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
    truth: Path = _TRUTH,
    paper: bool = _PAPER,
    overwrite: bool = overwrite_option(),
    scheduler: str = scheduler_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
):
    """Relative L2 errors (overall, per distance band, energy-weighted), error maps, profiles, HTML report: a
    planar model on its planar data set, or a per-vertex model on its mesh data set."""
    from ..workflow.evaluating import evaluate_report  # heavy: Dask and Matplotlib load only to evaluate

    evaluation = evaluate_report(
        model,
        data,
        report,
        compare=compare or (),
        points=points,
        truth=truth,
        json_out=json_out,
        overwrite=overwrite,
        scheduler=scheduler,
        max_memory=max_memory,
        reporter=RichReporter(quiet),
        paper=paper,
    )
    title = (
        f"relative L2 error against the truth {truth}"
        if truth
        else f"relative L2 error on {data} (in-sample)"
    )
    lines = [_table(evaluation, title, truth is not None), f"report: {evaluation.report / 'index.html'}"]
    finish(as_json, quiet, evaluation.summary, lines)


def _table(evaluation, title: str, held_out: bool) -> Table:
    """The errors per model (and the noise floor) as a table: planar models with their total reflectance,
    per-vertex models held out with their error beyond the noise."""
    summary, mesh = evaluation.summary, evaluation.geometry == "mesh"
    table = Table(title=title)
    columns = ["model", "all", "near <1 mm", "mid 1-4 mm", "far >4 mm"] + ([] if mesh else ["total refl."])
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
        f"[dim]{evaluation.noise}[/]",
        *(f"[dim]{100 * nf[k]:.2f} %[/]" for k in ("all", "near", "mid", "far")),
    )
    return table


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
