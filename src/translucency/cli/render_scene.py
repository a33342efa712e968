"""``translucency render scene``: fitted objects in a user's Mitsuba 3 scene — each prepared, lit by the scene
(light in, through the body), drawn through the scene's camera; with ``--reference`` the scene path-traced
with the objects' volumes in place and their comparison."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from .._validate import TranslucencyError, check_option
from ._common import (
    PANEL_SAMPLING,
    PANEL_TRANSPORT,
    finish,
    json_option,
    max_memory_option,
    overwrite_option,
    quiet_option,
    user_errors,
)
from ._run import RichReporter
from .render import _ANGLES, _EXPOSURE, _OUT, _PAPER, _RADIUS, _REFERENCE, _REFERENCE_SPP

# -- the options (their help is what --help shows) --------------------------------------------------
_SCENE = typer.Argument(
    ...,
    help="A Mitsuba 3 scene file (XML): its emitters, shapes, sensor and film as they are; name the fitted "
    "objects with --object (documentation: 'Fitted objects in your Mitsuba 3 scene').",
)
_OBJECTS = typer.Option(
    [],
    "--object",
    metavar="ID=FILE",
    help="The shape with this id is this per-vertex model (its mesh from 'translucency "
    "export MODEL --ply', placed by to_world). Repeat for several objects.",
)
_SCENE_UNIT = typer.Option(1.0, "--scene-unit", help="Millimetres per scene unit.")
_IRRADIANCE_SAMPLES = typer.Option(
    32,
    "--irradiance-samples",
    help="Irradiance samples per vertex of the first pass, path-traced (a later pass, the "
    "objects' glow alone, takes a quarter of them).",
    rich_help_panel=PANEL_SAMPLING,
)
_PASSES = typer.Option(
    2,
    "--passes",
    help="Light-in / through-the-body passes (2: the scene lit by the objects lights them back once).",
    rich_help_panel=PANEL_SAMPLING,
)
_MAX_DEPTH = typer.Option(
    8, "--max-depth", help="Longest light path, bounces.", rich_help_panel=PANEL_SAMPLING
)
_ROUGHNESS = typer.Option(
    0.0,
    "--roughness",
    help="GGX roughness of a dielectric object's boundary (0: smooth).",
    rich_help_panel=PANEL_TRANSPORT,
)
_PICTURE_SPP = typer.Option(
    16,
    "--picture-spp",
    help="Samples per pixel of our picture (anti-aliasing: the picture has no noise otherwise).",
    rich_help_panel=PANEL_SAMPLING,
)


@user_errors
def render_scene(
    scene: Path = _SCENE,
    objects: list[str] = _OBJECTS,
    out: Path = _OUT,
    scene_unit: float = _SCENE_UNIT,
    irradiance_samples: int = _IRRADIANCE_SAMPLES,
    passes: int = _PASSES,
    max_depth: int = _MAX_DEPTH,
    roughness: float = _ROUGHNESS,
    picture_spp: int = _PICTURE_SPP,
    exposure: str = _EXPOSURE,
    reference: bool = _REFERENCE,
    reference_spp: int = _REFERENCE_SPP,
    radius: float = _RADIUS,
    paper: bool = _PAPER,
    angles: bool = _ANGLES,
    overwrite: bool = overwrite_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Render fitted objects in a Mitsuba 3 scene: lit by its lights, drawn through its camera (EXR + PNG)."""  # noqa: E501 — Typer lists the docstring verbatim as the command's one-line help
    from ..workflow.scene_rendering import render_scene as render  # heavy: Mitsuba, Numba, trimesh

    check_option("--reference-spp", reference_spp, lo=1)  # the library's spp is acquire's --spp
    shot = render(
        scene, parse_objects(objects), out, scene_unit=scene_unit, samples=irradiance_samples,
        passes=passes, max_depth=max_depth, roughness=roughness, picture_spp=picture_spp, exposure=exposure,
        reference=reference, spp=reference_spp, radius=radius, paper=paper, angles=angles,
        overwrite=overwrite, max_memory=max_memory, reporter=RichReporter(quiet),
    )  # fmt: skip
    finish(as_json, quiet, shot.summary, [_scene_table(scene, shot.summary, reference), f"images: {out}"])


def parse_objects(texts: list[str]) -> dict[str, Path]:
    """``ID=FILE`` pairs (``--object``) as {id: path}; one line for a malformed or repeated one."""
    out: dict[str, Path] = {}
    for text in texts:
        key, eq, path = text.partition("=")
        if not eq or not key.strip() or not path.strip():
            raise TranslucencyError(
                f"--object {text!r}: expected ID=FILE (a shape id of the scene = a model file)"
            )
        if key.strip() in out:
            raise TranslucencyError(f"--object: the shape id {key.strip()!r} is given twice")
        out[key.strip()] = Path(path.strip())
    if not out:
        raise TranslucencyError(
            "render scene: name the fitted objects with --object ID=FILE (shape id = model file)"
        )
    return out


def _scene_table(scene: Path, summary: dict, reference: bool) -> Table:
    """The scene render's numbers: times, pixels, and with a reference the errors per region."""
    table = Table(title=f"render of {scene.name}", show_header=False)
    for key in ("prepare_s", "light_s", "draw_s", "object_pixels"):
        table.add_row(key, f"{summary[key]:.4g}")
    if reference:
        for part in ("object", "lit", "rest"):
            e = summary["errors"][part]
            if e.get("pixels"):
                table.add_row(f"{part}: rel. RMSE", f"{e['rel_rmse']:.4g} ({e['pixels']:,} px)")
        table.add_row("object: FLIP", f"{summary['errors']['object']['flip']:.4g}")
        table.add_row("reference noise", f"{summary['reference_noise']:.4g}")
    return table
