"""``translucency export``: a per-vertex model taken to other tools — its mesh as a PLY for a Mitsuba scene
(``render scene``), in the model's millimetres and vertex order; or as glTF 2.0 (``--gltf``) for Blender
and three.js: the mesh, the exitance under a light baked as vertex colours, and each vertex's profile
reduced to Christensen–Burley's albedo and mean free path per channel (with the reduction's error); or the
medium estimated from the scan, filling the mesh, as a Mitsuba 3 scene to path-trace (``--mitsuba``):
:func:`translucency.workflow.exporting.export_model`."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import (
    PANEL_LIGHT,
    PANEL_TRANSPORT,
    finish,
    json_option,
    max_memory_option,
    overwrite_option,
    quiet_option,
    user_errors,
)

#: the light baked when none is given (the library's ``DEFAULT_LIGHT``, stated here so that ``--help``
#: loads no renderer)
DEFAULT_LIGHT = "point@key"


_MODEL = typer.Argument(..., help="A per-vertex model file (translucency fit on a mesh data set).")

_PLY = typer.Option(
    None,
    "--ply",
    help="Write the model's mesh here (binary PLY, mm, the model's vertex order): the shape a Mitsuba "
    "scene places with its to_world for render scene.",
)

_GLTF = typer.Option(
    None,
    "--gltf",
    help="Write glTF 2.0 binary here (.glb, metres): the mesh, the exitance under --light baked as "
    "vertex colours (COLOR_0, linear, scaled into [0, 1]: the scale in the file's extras) and per-vertex "
    "attributes _ALBEDO, _MFP_MM, _BURLEY_S (Christensen-Burley per channel) and _REDUCTION_ERROR.",
)

_MITSUBA = typer.Option(
    None,
    "--mitsuba",
    metavar="DIR",
    help="Write a Mitsuba 3 scene into this folder: scene.xml (volpath; the mesh filled with the medium "
    "estimated from the scan, a heterogeneous medium behind an index-matched null boundary; a default "
    "camera and the --light to keep or replace), object.ply (mm) and the medium as grid volumes "
    "sigma_t.vol (extinction, 1/mm, RGB) and albedo.vol (RGB). The model must be fitted with this "
    "version.",
)

_LIGHT = typer.Option(
    DEFAULT_LIGHT,
    "--light",
    metavar="LIGHT",
    help="With --gltf: the light baked (as render's); with --mitsuba: the scene's emitter.",
    rich_help_panel=PANEL_LIGHT,
)

_ANGLES = typer.Option(
    False,
    "--angles",
    help="With --gltf: bake the model's lean (the transport leaned toward the light, as render "
    "--angles); a model without one bakes the paper's model.",
    rich_help_panel=PANEL_TRANSPORT,
)


@user_errors
def export(
    model: Path = _MODEL,
    ply: Path = _PLY,
    gltf: Path = _GLTF,
    mitsuba: Path = _MITSUBA,
    light: str = _LIGHT,
    angles: bool = _ANGLES,
    overwrite: bool = overwrite_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Take a per-vertex model to other tools: its mesh as PLY (render scene) or glTF (Blender), its medium
    as a Mitsuba 3 scene."""
    from ..workflow.exporting import export_model  # heavy: the bake loads Mitsuba and the transport

    summary = export_model(
        model,
        ply=ply,
        gltf=gltf,
        mitsuba=mitsuba,
        light=light,
        angles=angles,
        overwrite=overwrite,
        max_memory=max_memory,
    )
    lines = []
    if ply is not None:
        lines.append(f"mesh: {ply} ({summary['vertices']:,} vertices, {summary['faces']:,} triangles, mm)")
    if gltf is not None:
        leaned = ", leaned" if summary["angles"] else ""
        lines.append(
            f"glTF: {gltf} (baked under {light}{leaned}; Burley reduction error median "
            f"{summary['reduction_error_median']:.3f}, 95th percentile {summary['reduction_error_p95']:.3f})"
        )
    if mitsuba is not None:
        grid = " x ".join(str(n) for n in summary["voxels"])
        lines.append(
            f"Mitsuba scene: {summary['mitsuba']} (the estimated medium, {grid} voxels of "
            f"{summary['voxel_mm']:.3g} mm; render it with: mitsuba {summary['mitsuba']})"
        )
    if "lean" in summary:
        lines.append(summary["lean"])
    finish(as_json, quiet, summary, lines)
