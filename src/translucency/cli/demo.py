"""``translucency demo``: the main job on the embedded default data
(:func:`translucency.workflow.run_demo`)."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import console, overwrite_option, user_errors
from ._run import RichReporter


@user_errors
def demo(
    out: Path = typer.Option(Path("results"), "--out", "-o", help="Directory for the figures and files."),
    terms: int = typer.Option(3, "--terms", "-n", min=1, max=8, help="Exponential terms n of the fits."),
    overwrite: bool = overwrite_option(),
):
    """The main job on the embedded default data: baselines per material, then planar fits
    (iso, aniso, dipole, Burley) with alpha and the Figure 1 report."""
    from ..workflow.demo import run_demo  # heavy: the main job loads every stage and Mitsuba

    outputs = run_demo(out, n_terms=terms, overwrite=overwrite, reporter=RichReporter(False))
    for what, path in outputs.items():
        console.print(f"{what:>8}: {path}")
