"""``translucency export``: a per-vertex model taken to other tools — its mesh as a PLY for a Mitsuba scene
(``render --scene``), in the model's millimetres and vertex order."""

from __future__ import annotations

from pathlib import Path

import typer

from .._validate import TranslucencyError
from ..io.atomic import atomic_path
from ..io.inputs import expect_input
from ..io.model_file import load_model, read_header
from ..io.outputs import PLY_COMMENT, claim_output
from ._common import finish, json_option, overwrite_option, quiet_option, user_errors


@user_errors
def export(
    model: Path = typer.Argument(..., help="A per-vertex model file (translucency fit on a mesh data set)."),
    ply: Path = typer.Option(
        None,
        "--ply",
        help="Write the model's mesh here (binary PLY, mm, the model's vertex order): the shape a Mitsuba "
        "scene places with its to_world for render --scene.",
    ),
    overwrite: bool = overwrite_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Take a per-vertex model to other tools: its mesh as PLY (for render --scene)."""
    from ..mitsuba import write_ply  # Mitsuba's scene helpers: loaded only to write
    from ..render import object_of_model

    if ply is None:
        raise TranslucencyError("export: say what to write (--ply OUT.ply)")
    if ply.suffix.lower() != ".ply":
        raise TranslucencyError(f"--ply {ply}: the file name must end in .ply")
    expect_input(model, ("model file",))
    m = load_model(model)
    if m.geometry != "mesh":
        raise TranslucencyError(
            f"{model}: a planar model has no mesh to export; export takes a per-vertex model"
        )
    mesh, _ = object_of_model(m, read_header(model))
    claim_output(ply, "mesh file", overwrite=overwrite, inputs=[model], option="--ply")
    with atomic_path(ply) as tmp:
        write_ply(tmp, mesh.vertices, mesh.faces, comment=PLY_COMMENT)
    finish(
        as_json,
        quiet,
        {
            "command": "export",
            "model": model,
            "ply": ply,
            "vertices": len(mesh.vertices),
            "faces": len(mesh.faces),
        },
        [f"mesh: {ply} ({len(mesh.vertices):,} vertices, {len(mesh.faces):,} triangles, mm)"],
    )
