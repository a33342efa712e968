"""``translucency examples``: the documentation's example files into a folder
(:func:`translucency.workflow.examples.copy_examples`)."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import PANEL_RUN, finish, json_option, quiet_option, user_errors
from ._run import RichReporter

_OUT = typer.Argument(..., help="The folder to copy them into (made if missing).")
_OVERWRITE = typer.Option(
    False,
    "--overwrite",
    help="Replace files of the same names with other contents (else refused).",
    rich_help_panel=PANEL_RUN,
)


@user_errors
def examples(
    out: Path = _OUT,
    overwrite: bool = _OVERWRITE,
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Copy the example files into OUT: spot.obj and cow.obj (meshes in mm, +z up), sky.exr (a sky),
    scene.xml (a Mitsuba scene around object.ply), filling.npz (a volume for --volume),
    spot_coarse.model.zip (a small fitted model to render at once) and LICENSES.md."""
    from ..workflow.examples import copy_examples  # the package's data folder and the atomic writes

    done = copy_examples(out, overwrite=overwrite, reporter=RichReporter(quiet or as_json))
    written = ", ".join(done["written"]) or "nothing new"
    finish(as_json, quiet, done, [f"examples in {done['out']}: {written}"])
