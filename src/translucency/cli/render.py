"""``translucency render``: a fitted object relit — its prepared transport drawn through Mitsuba (EXR + PNG),
and with ``--reference`` the path-traced reference and their comparison.  A user's scene:
:mod:`.render_scene`."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from .._validate import TranslucencyError, check_option
from ._common import (
    PANEL_CAMERA,
    PANEL_COMPARISON,
    PANEL_LIGHT,
    PANEL_OUTPUT,
    PANEL_TRANSPORT,
    finish,
    json_option,
    max_memory_option,
    overwrite_option,
    quiet_option,
    user_errors,
)
from ._run import RichReporter

#: the light of a render when none is given (the library's ``DEFAULT_LIGHT``, stated here so that
#: ``--help`` loads no renderer)
DEFAULT_LIGHT = "point@key"
#: the camera direction and picture resolution when none is given (the library's defaults)
DEFAULT_VIEW, DEFAULT_RESOLUTION = "1,-1.6,0.7", (320, 240)


# -- the options (their help is what --help shows) --------------------------------------------------
_MODEL = typer.Argument(..., help="A per-vertex model file (translucency fit on a mesh data set).")
_OUT = typer.Option(Path("render"), "--out", "-o", help="Directory for ours.exr/.png (and the reference).")
_LIGHT = typer.Option(
    [DEFAULT_LIGHT],
    "--light",
    metavar="LIGHT",
    help="In the object's frame (mm, +z up; the render prints the object's centre and size): "
    "point:x,y,z[,I] (at x,y,z; I in W/sr) | spot:x,y,z,tx,ty,tz,cutoff[,I] (at x,y,z aimed at "
    "tx,ty,tz, cone half-angle in degrees) | directional:dx,dy,dz[,E] (dx,dy,dz: the direction the "
    "light TRAVELS, 0,0,-1 shines down; E in W/mm^2) | env:L (a constant sky, W/(mm^2 sr)) | "
    "env:MAP.exr[,scale] (a latitude-longitude map, its +Y turned to +z). Relative to the object: "
    "point@AZ,EL[,DIST[,I]] | spot@AZ,EL[,DIST[,CUTOFF[,I]]] (aimed at the centre) | "
    "directional@AZ,EL[,E] (coming FROM AZ,EL): AZ degrees from +x towards +y, EL degrees above the "
    "xy plane, around the object's centre; DIST in mm or object sizes with x (2x; size = the "
    "bounding box's diagonal; default 1.5x); AZ,EL may be camera (from the "
    "camera's side) or back (behind the object). Without I or E: 1e4 W/sr, 1 W/mm^2.",
    rich_help_panel=PANEL_LIGHT,
)
_VIEW = typer.Option(
    DEFAULT_VIEW,
    "--view",
    metavar="X,Y,Z",
    help="Direction from the object's centre towards the camera, x,y,z in the object's frame "
    "(+z up); the camera looks at the centre from 1.9 object sizes.",
    rich_help_panel=PANEL_CAMERA,
)
_EXPOSURE = typer.Option(
    "fixed",
    "--exposure",
    metavar="HOW",
    help="Exposure of the PNGs: fixed (from the object and the light's power alone, the same for "
    "every render of this object under lights of one power), fixed+STOPS / fixed-STOPS (brighter / "
    "darker by that many stops), auto (per picture: its brightest 1% at 0.8) or a factor on the "
    "linear radiance (the 'exposure' render.json states, to match another render). The EXRs are "
    "linear whatever the exposure.",
    rich_help_panel=PANEL_OUTPUT,
)
_RESOLUTION = typer.Option(
    DEFAULT_RESOLUTION, "--resolution", help="Image width and height, pixels.", rich_help_panel=PANEL_CAMERA
)
_REFERENCE = typer.Option(
    False,
    "--reference",
    help="Also path-trace the reference (Mitsuba volpath) and compare.",
    rich_help_panel=PANEL_COMPARISON,
)
_REFERENCE_SPP = typer.Option(
    32,
    "--reference-spp",
    help="Samples per pixel of each of the two path-traced reference renders (with --reference).",
    rich_help_panel=PANEL_COMPARISON,
)
_RADIUS = typer.Option(
    None,
    "--radius",
    help="Near radius of the transport, mm: pairs within it summed exactly, those beyond it through the "
    "hierarchical far field (default: the 99% energy radius, or less where the pairs would not fit in a "
    "quarter of --max-memory or of the machine's memory). A smaller radius lowers the memory.",
    rich_help_panel=PANEL_TRANSPORT,
)
_PAPER = typer.Option(
    False,
    "--paper",
    help="Draw the paper's model: each point's radial profile alone, without the through-body table the "
    "model holds (light between sides whose normals face apart, measured against the fit; drawn by default; "
    "documentation: 'Light through the body').",
    rich_help_panel=PANEL_TRANSPORT,
)
_TRANSPORT = typer.Option(
    None,
    "--transport",
    metavar="KIND",
    help="The transport drawn: default (the fitted model with its through-body table) | walked (the "
    "model's near field, and the light that crosses the body walked through the medium the fit estimated "
    "from the scan, entered along the light's own direction; back-lit objects; documentation: 'Light "
    "through the body') | "
    "paper (as --paper).",
    rich_help_panel=PANEL_TRANSPORT,
)
_ANGLES = typer.Option(
    False,
    "--angles",
    help="Lean the transport toward the light's direction (the model's lean, fitted from a data set "
    "acquired with --incidence): back-lit objects (documentation: 'The light's direction: angle axes and the "
    "lean'). A light of many "
    "directions (env, a scene's) leans by its irradiance-weighted mean direction; a model without a lean "
    "is drawn without it.",
    rich_help_panel=PANEL_TRANSPORT,
)


@user_errors
def render(
    model: Path = _MODEL,
    out: Path = _OUT,
    light: list[str] = _LIGHT,
    view: str = _VIEW,
    exposure: str = _EXPOSURE,
    resolution: tuple[int, int] = _RESOLUTION,
    reference: bool = _REFERENCE,
    reference_spp: int = _REFERENCE_SPP,
    radius: float = _RADIUS,
    paper: bool = _PAPER,
    transport: str = _TRANSPORT,
    angles: bool = _ANGLES,
    overwrite: bool = overwrite_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Relight a fitted object: its transport drawn through Mitsuba (EXR + PNG); in a scene: render scene."""  # noqa: E501 — Typer lists the docstring verbatim as the command's one-line help; a line break would show in `translucency --help`
    from ..workflow.rendering import render_model  # heavy: Mitsuba, Numba, trimesh

    if len(light) > 1:
        raise TranslucencyError("--light: one light per render for now (run once per light)")
    check_option("--reference-spp", reference_spp, lo=1)  # the library's spp is acquire's --spp
    rendering = render_model(
        model, out, light=light[0], view=view, resolution=resolution, exposure=exposure, reference=reference,
        spp=reference_spp, radius=radius, paper=paper, transport=transport, angles=angles,
        overwrite=overwrite, max_memory=max_memory, reporter=RichReporter(quiet),
    )  # fmt: skip
    table = Table(title=f"render of {model.name}", show_header=False)
    for k, v in rendering.numbers.items():
        table.add_row(k, f"{v:.4g}" if isinstance(v, float) else str(v))
    finish(as_json, quiet, rendering.summary, [table, f"images: {out}"])
