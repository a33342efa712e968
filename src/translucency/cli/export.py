"""``translucency export``: a per-vertex model taken to other tools — its mesh as a PLY for a Mitsuba scene
(``render --scene``), in the model's millimetres and vertex order; or as glTF 2.0 (``--gltf``) for Blender
and three.js: the mesh, the exitance under a light baked as vertex colours, and each vertex's profile
reduced to Christensen–Burley's albedo and mean free path per channel (with the reduction's error)."""

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
    gltf: Path = typer.Option(
        None,
        "--gltf",
        help="Write glTF 2.0 binary here (.glb, metres): the mesh, the exitance under --light baked as "
        "vertex colours (COLOR_0, linear, scaled into [0, 1]: the scale in the file's extras) and per-vertex "
        "attributes _ALBEDO, _MFP_MM, _BURLEY_S (Christensen-Burley per channel) and _REDUCTION_ERROR.",
    ),
    light: str = typer.Option(
        "point:60,-80,120,2e4", "--light", metavar="LIGHT", help="With --gltf: the light baked (as render's)."
    ),
    overwrite: bool = overwrite_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Take a per-vertex model to other tools: its mesh as PLY (render --scene) or glTF (Blender)."""
    from ..mitsuba import write_ply  # Mitsuba's scene helpers: loaded only to write
    from ..render import object_of_model

    if ply is None and gltf is None:
        raise TranslucencyError("export: say what to write (--ply OUT.ply or --gltf OUT.glb)")
    if ply is not None and ply.suffix.lower() != ".ply":
        raise TranslucencyError(f"--ply {ply}: the file name must end in .ply")
    if gltf is not None and gltf.suffix.lower() != ".glb":
        raise TranslucencyError(f"--gltf {gltf}: the file name must end in .glb (binary glTF)")
    expect_input(model, ("model file",))
    m = load_model(model)
    if m.geometry != "mesh":
        raise TranslucencyError(
            f"{model}: a planar model has no mesh to export; export takes a per-vertex model"
        )
    mesh, acquisition = object_of_model(m, read_header(model))
    summary = {"command": "export", "model": model, "vertices": len(mesh.vertices), "faces": len(mesh.faces)}
    lines = []
    if ply is not None:
        claim_output(ply, "mesh file", overwrite=overwrite, inputs=[model], option="--ply")
        with atomic_path(ply) as tmp:
            write_ply(tmp, mesh.vertices, mesh.faces, comment=PLY_COMMENT)
        summary["ply"] = ply
        lines.append(f"mesh: {ply} ({len(mesh.vertices):,} vertices, {len(mesh.faces):,} triangles, mm)")
    if gltf is not None:
        from .export_gltf import export_gltf  # the bake loads Mitsuba and the transport

        claim_output(gltf, "mesh file", overwrite=overwrite, inputs=[model], option="--gltf")
        record = export_gltf(m, mesh, acquisition, gltf, light)
        summary.update(gltf=gltf, **record)
        lines.append(
            f"glTF: {gltf} (baked under {light}; Burley reduction error median "
            f"{record['reduction_error_median']:.3f}, 95th percentile {record['reduction_error_p95']:.3f})"
        )
    finish(as_json, quiet, summary, lines)
