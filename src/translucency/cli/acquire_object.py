"""``translucency acquire object-photographs``: a virtual object rig — Mitsuba 3 photographs of a filled
mesh lit by a laser at surface points, from calibrated cameras around it — written as a lab would hand
them to ``translucency import object``."""

from __future__ import annotations

from pathlib import Path

import typer

from ..workflow import GENERATORS
from ._common import (
    PANEL_CAMERA,
    PANEL_OUTPUT,
    PANEL_SAMPLE,
    PANEL_SCAN,
    boundary_eta,
    eta_option,
    finish,
    index_matched_option,
    json_option,
    max_memory_option,
    overwrite_option,
    quiet_option,
    user_errors,
    voxel_option,
)
from ._run import RichReporter

SAMPLES = ", ".join(GENERATORS) + " (<name>: one of `translucency materials`)"


class ObjectPhotographsOptions:
    """The options of ``acquire object-photographs`` (a class of their own keeps the command short)."""

    out = typer.Option(..., "--out", "-o", help="Output folder: object.json, object.ply, cameras, shots.")
    mesh = typer.Option(None, "--mesh", help="Mesh file (OBJ/PLY/STL); default the built-in pig.")
    scale = typer.Option(1.0, "--scale", help="Millimetres per mesh-file unit.", rich_help_panel=PANEL_SAMPLE)
    up = typer.Option(
        "z", "--up", help="The mesh file's up axis (z, y or x), turned to +z.", rich_help_panel=PANEL_SAMPLE
    )
    material = typer.Option("marble", "--material", "-m", help=f"Filling: {SAMPLES}.")
    voxel = voxel_option(0.5)
    points = typer.Option(
        8,
        "--points",
        help="Laser positions (farthest-point sample of the vertices).",
        rich_help_panel=PANEL_SCAN,
    )
    cameras = typer.Option(
        6, "--cameras", help="Cameras on a sphere around the object.", rich_help_panel=PANEL_CAMERA
    )
    resolution = typer.Option(
        (128, 128), "--resolution", help="Image width and height, pixels.", rich_help_panel=PANEL_CAMERA
    )
    spp = typer.Option(
        64,
        "--spp",
        help="Samples per pixel of the path-traced photographs (each of the two repeated frames).",
        rich_help_panel=PANEL_CAMERA,
    )
    beam = typer.Option(
        0.3, "--beam", help="Radius of the laser's spot on the surface, mm.", rich_help_panel=PANEL_SCAN
    )
    eta = eta_option("1.3 for the generated materials; > 1: the laser enters through a window over its spot")
    index_matched = index_matched_option()
    checkerboards = typer.Option(
        False,
        "--checkerboards",
        help="Give intrinsics as checkerboard photographs (OpenCV calibrates).",
        rich_help_panel=PANEL_CAMERA,
    )
    exposures = typer.Option(
        "brackets",
        "--exposures",
        help="brackets (two long exposures and a short one a camera and shot) or single (the spot clipped).",
        rich_help_panel=PANEL_CAMERA,
    )
    seed = typer.Option(0, "--seed", help="Random seed of the filling, the renders and the sensor.")
    preview = typer.Option(
        False,
        "--preview",
        help="A quick rehearsal: --points 4 --cameras 4 --resolution 48 36 --spp 4 --voxel 1 where those "
        "options are not given (a first imported object in minutes, not a model to trust).",
    )
    image_format = typer.Option("pfm", "--format", help="pfm or exr.", rich_help_panel=PANEL_OUTPUT)
    overwrite = overwrite_option()
    max_memory = max_memory_option()
    quiet = quiet_option()
    as_json = json_option()


@user_errors
def acquire_object_photographs_cmd(
    ctx: typer.Context,
    out: Path = ObjectPhotographsOptions.out,
    mesh: Path = ObjectPhotographsOptions.mesh,
    scale: float = ObjectPhotographsOptions.scale,
    up: str = ObjectPhotographsOptions.up,
    material: str = ObjectPhotographsOptions.material,
    voxel: float = ObjectPhotographsOptions.voxel,
    points: int = ObjectPhotographsOptions.points,
    cameras: int = ObjectPhotographsOptions.cameras,
    resolution: tuple[int, int] = ObjectPhotographsOptions.resolution,
    spp: int = ObjectPhotographsOptions.spp,
    beam: float = ObjectPhotographsOptions.beam,
    eta: float = ObjectPhotographsOptions.eta,
    index_matched: bool = ObjectPhotographsOptions.index_matched,
    checkerboards: bool = ObjectPhotographsOptions.checkerboards,
    exposures: str = ObjectPhotographsOptions.exposures,
    seed: int = ObjectPhotographsOptions.seed,
    preview: bool = ObjectPhotographsOptions.preview,
    image_format: str = ObjectPhotographsOptions.image_format,
    overwrite: bool = ObjectPhotographsOptions.overwrite,
    max_memory: str = ObjectPhotographsOptions.max_memory,
    quiet: bool = ObjectPhotographsOptions.quiet,
    as_json: bool = ObjectPhotographsOptions.as_json,
):
    """Photograph a virtual object with Mitsuba 3 (a laser spot per point, N calibrated cameras, sensor noise,
    dark offset, vignetting, a saturated spot, drifting power): a lab's hand-over for `import object`."""
    # heavy: Mitsuba and trimesh load only when it runs
    from ..workflow.photographing import acquire_object_photographs

    # the settings the command line gave; with --preview the others are the workflow's rehearsal's
    given = {"points": points, "cameras": cameras, "resolution": resolution, "spp": spp, "voxel_mm": voxel}
    if preview:
        option = {"voxel_mm": "voxel"}
        given = {k: None if ctx.get_parameter_source(option.get(k, k)).name == "DEFAULT" else v
                 for k, v in given.items()}  # fmt: skip
    shots = acquire_object_photographs(
        mesh,
        out,
        sample=material,
        scale_mm=scale,
        up=up,
        **given,
        preview=preview,
        beam_mm=beam,
        eta=boundary_eta(eta, index_matched),
        checkerboards=checkerboards,
        exposures=exposures,
        seed=seed,
        image_format=image_format,
        overwrite=overwrite,
        max_memory=max_memory,
        reporter=RichReporter(quiet),
    )
    line = f"photographs: {shots.folder / 'object.json'} (import with `translucency import object`)"
    finish(as_json, quiet, shots.summary, [line])
