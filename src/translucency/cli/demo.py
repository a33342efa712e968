"""``translucency demo``: the paper's two figures reproduced on the embedded default data
(:func:`translucency.workflow.run_demo`)."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import finish, json_option, max_memory_option, overwrite_option, quiet_option, user_errors
from ._run import RichReporter


@user_errors
def demo(
    out: Path = typer.Option(Path("results"), "--out", "-o", help="Directory for the figures and files."),
    terms: int = typer.Option(
        3,
        "--terms",
        "-n",
        help="Exponential terms n (1-4, as in fit) of the sum of exponentials fitted to each material's "
        "dipole profile (the baselines).",
    ),
    overwrite: bool = overwrite_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """The paper's figures from the embedded data: baselines per material; Figure 1 (the default fit, the
    paper's, iso, dipole and Burley, scored against an independent scan); Figure 2 (a marble pig fitted per
    vertex and rendered beside a path-traced reference)."""
    from ..workflow.demo import run_demo  # heavy: the demo loads every stage and Mitsuba

    outputs = run_demo(
        out, n_terms=terms, overwrite=overwrite, max_memory=max_memory, reporter=RichReporter(quiet)
    )
    summary = {"command": "demo", "out": out, "outputs": outputs}
    finish(as_json, quiet, summary, [f"{what:>8}: {path}" for what, path in outputs.items()])
