"""``translucency demo``: the main job on the embedded default data
(:func:`translucency.pipeline.run_demo`)."""

from __future__ import annotations

from pathlib import Path

import typer

from ..model import MATERIALS
from ._common import console, overwrite_option, progress, user_errors


@user_errors
def demo(
    out: Path = typer.Option(Path("results"), "--out", "-o", help="Directory for the figures and files."),
    terms: int = typer.Option(3, "--terms", "-n", min=1, max=8, help="Exponential terms n of the fits."),
    overwrite: bool = overwrite_option(),
):
    """The main job on the embedded default data: baselines per material, then planar fits
    (iso, aniso, dipole, Burley) with alpha and the Figure 1 report."""
    from ..pipeline import DEMO_FITS, run_demo  # heavy: the main job loads every stage and Mitsuba

    with progress() as bar:
        task = bar.add_task("demo", total=len(MATERIALS) + len(DEMO_FITS) + 3, item="")

        def step(name):
            bar.update(task, advance=1, item=name)

        outputs = run_demo(out, n_terms=terms, step=step, overwrite=overwrite)
    for what, path in outputs.items():
        console.print(f"{what:>8}: {path}")
