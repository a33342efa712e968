"""``translucency render``: a fitted object relit — irradiance per vertex, the sparse transport, a picture
through Mitsuba (EXR + PNG), and with ``--reference`` the path-traced reference and their comparison."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from .._validate import TranslucencyError
from ._common import finish, json_option, max_memory_option, overwrite_option, quiet_option, user_errors
from ._run import RichReporter

#: the light of a render when none is given (the library's ``DEFAULT_LIGHT``, stated here so that
#: ``--help`` loads no renderer)
DEFAULT_LIGHT = "point:60,-80,120,2e4"
#: the camera direction and picture resolution when none is given (the library's defaults)
DEFAULT_VIEW, DEFAULT_RESOLUTION = "1,-1.6,0.7", (320, 240)


# -- the options (their help is what --help shows) --------------------------------------------------
_MODEL = typer.Argument(
    None, help="A per-vertex model file (translucency fit on a mesh data set); none with --scene."
)
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
)
_VIEW = typer.Option(
    DEFAULT_VIEW,
    "--view",
    metavar="X,Y,Z",
    help="Direction from the object's centre towards the camera, x,y,z in the object's frame "
    "(+z up); the camera looks at the centre from 1.9 object sizes.",
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
)
_RESOLUTION = typer.Option(DEFAULT_RESOLUTION, "--resolution", help="Image width and height, pixels.")
_REFERENCE = typer.Option(
    False, "--reference", help="Also path-trace the reference (Mitsuba volpath) and compare."
)
_SPP = typer.Option(32, "--spp", help="Samples per pixel of each of the two reference renders.")
_RADIUS = typer.Option(
    None,
    "--radius",
    help="Near radius of the transport, mm: pairs within it summed exactly, those beyond it through the "
    "hierarchical far field (default: the 99% energy radius, or less where the pairs would not fit in a "
    "quarter of --max-memory or of the machine's memory). A smaller radius lowers the memory.",
)
_INCIDENCE_LAW = typer.Option(
    "half-space",
    "--incidence-law",
    metavar="LAW",
    help="How light arriving at an angle counts against the data's normal-incidence beams: 'half-space' "
    "(Chandrasekhar's plane albedo per vertex from its measured total: oblique light comes back more, "
    "and by reciprocity leaves more toward oblique views; index-matched objects), 'half-space-in' (the "
    "light in only, a Lambertian exit) or 'normal' (every direction as measured).",
)
_PAPER = typer.Option(
    False,
    "--paper",
    help="Draw the paper's model: each point's radial profile alone, without the through-body table the "
    "model holds (light between sides whose normals face apart, measured against the fit; drawn by default, "
    "docs/through-body.md).",
)
_ANGLES = typer.Option(
    False,
    "--angles",
    help="Lean the transport toward the light's direction (the model's lean, fitted from a data set "
    "acquired with --incidence; model/lean.py): back-lit objects, docs/lean.md. A light of many "
    "directions (env, a scene's) leans by its irradiance-weighted mean direction; a model without a lean "
    "is drawn without it.",
)
_SCENE = typer.Option(
    None,
    "--scene",
    help="A Mitsuba 3 scene file (XML) to render the fitted objects in: its emitters, shapes, sensor "
    "and film as they are; name the objects with --object (docs/scenes.md).",
)
_OBJECTS = typer.Option(
    [],
    "--object",
    metavar="ID=FILE",
    help="With --scene: the shape with this id is this per-vertex model (its mesh from 'translucency "
    "export MODEL --ply', placed by to_world). Repeat for several objects.",
)
_SCENE_UNIT = typer.Option(1.0, "--scene-unit", help="With --scene: millimetres per scene unit.")
_SAMPLES = typer.Option(
    32,
    "--samples",
    help="With --scene: irradiance samples per vertex of the first pass, path-traced (a later pass, the "
    "objects' glow alone, takes a quarter of them).",
)
_PASSES = typer.Option(
    2,
    "--passes",
    help="With --scene: light-in / through-the-body passes (2: the scene lit by the objects "
    "lights them back once).",
)
_MAX_DEPTH = typer.Option(8, "--max-depth", help="With --scene: longest light path, bounces.")
_ROUGHNESS = typer.Option(
    0.0, "--roughness", help="With --scene: GGX roughness of a dielectric object's boundary (0: smooth)."
)
_PICTURE_SPP = typer.Option(16, "--picture-spp", help="With --scene: samples per pixel of our picture.")


@user_errors
def render(
    model: Path = _MODEL,
    out: Path = _OUT,
    light: list[str] = _LIGHT,
    view: str = _VIEW,
    exposure: str = _EXPOSURE,
    resolution: tuple[int, int] = _RESOLUTION,
    reference: bool = _REFERENCE,
    spp: int = _SPP,
    radius: float = _RADIUS,
    incidence_law: str = _INCIDENCE_LAW,
    paper: bool = _PAPER,
    angles: bool = _ANGLES,
    scene: Path = _SCENE,
    objects: list[str] = _OBJECTS,
    scene_unit: float = _SCENE_UNIT,
    samples: int = _SAMPLES,
    passes: int = _PASSES,
    max_depth: int = _MAX_DEPTH,
    roughness: float = _ROUGHNESS,
    picture_spp: int = _PICTURE_SPP,
    overwrite: bool = overwrite_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Relight a fitted object: irradiance per vertex, sparse transport, a picture through Mitsuba (EXR + PNG)."""  # noqa: E501 — Typer lists the docstring verbatim as the command's one-line help; a line break would show in `translucency --help`
    from ..workflow.rendering import render_model, render_scene  # heavy: Mitsuba, Numba, trimesh

    # what both kinds of render take, as the library names it
    common = dict(incidence_law=incidence_law, radius=radius, exposure=exposure, reference=reference, spp=spp)
    common.update(overwrite=overwrite, max_memory=max_memory, reporter=RichReporter(quiet))
    if scene is not None:
        _refuse_object_options(model, light, view, resolution)
        per_scene = dict(scene_unit=scene_unit, samples=samples, passes=passes, max_depth=max_depth)
        per_scene.update(angles=angles, paper=paper)
        per_scene.update(roughness=roughness, picture_spp=picture_spp)
        shot = render_scene(scene, parse_objects(objects), out, **per_scene, **common)
        finish(as_json, quiet, shot.summary, [_scene_table(scene, shot.summary, reference), f"images: {out}"])
        return
    if objects:
        raise TranslucencyError("--object: names the objects of a --scene; give the scene file too")
    if model is None:
        raise TranslucencyError("render: give a per-vertex model file, or --scene SCENE.xml --object ID=FILE")
    if len(light) > 1:
        raise TranslucencyError("--light: one light per render for now (run once per light)")
    rendering = render_model(
        model, out, light=light[0], view=view, resolution=resolution, paper=paper, angles=angles, **common
    )
    table = Table(title=f"render of {model.name}", show_header=False)
    for k, v in rendering.numbers.items():
        table.add_row(k, f"{v:.4g}" if isinstance(v, float) else str(v))
    finish(as_json, quiet, rendering.summary, [table, f"images: {out}"])


def _refuse_object_options(model, light, view, resolution) -> None:
    """With --scene the scene file says where the light and the camera are: one line for an option that
    would be ignored."""
    if model is not None:
        raise TranslucencyError(f"{model}: with --scene, name the objects with --object ID=FILE instead")
    given = [
        f
        for f, v, d in (
            ("--light", light, [DEFAULT_LIGHT]),
            ("--view", view, DEFAULT_VIEW),
            ("--resolution", tuple(resolution), DEFAULT_RESOLUTION),
        )
        if v != d
    ]
    if given:
        raise TranslucencyError(
            f"{given[0]}: the scene file says this (its emitters, sensor and film); not with --scene"
        )


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
            "--scene: name the fitted objects with --object ID=FILE (shape id = model file)"
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
