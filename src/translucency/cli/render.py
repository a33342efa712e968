"""``translucency render``: a fitted object relit — irradiance per vertex, the sparse transport, a picture
through Mitsuba (EXR + PNG), and with ``--reference`` the path-traced reference and their comparison."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from .. import resources
from .._validate import TranslucencyError, check_option
from ..io.inputs import expect_input
from ..io.model_file import load_model, read_header
from ._common import json_option, max_memory_option, overwrite_option, quiet_option, user_errors
from ._run import Run
from .render_scene import render_scene

#: the light of a render when none is given: above and in front of the default view, in mm
DEFAULT_LIGHT = "point:60,-80,120,2e4"


@user_errors
def render(
    model: Path = typer.Argument(
        None, help="A per-vertex model file (translucency fit on a mesh data set); none with --scene."
    ),
    out: Path = typer.Option(
        Path("render"), "--out", "-o", help="Directory for ours.exr/.png (and the reference)."
    ),
    light: list[str] = typer.Option(
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
    ),
    view: str = typer.Option(
        "1,-1.6,0.7",
        "--view",
        metavar="X,Y,Z",
        help="Direction from the object's centre towards the camera, x,y,z in the object's frame "
        "(+z up); the camera looks at the centre from 1.9 object sizes.",
    ),
    exposure: str = typer.Option(
        "fixed",
        "--exposure",
        metavar="HOW",
        help="Exposure of the PNGs: fixed (from the object and the light's power alone, the same for "
        "every render of this object under lights of one power), fixed+STOPS / fixed-STOPS (brighter / "
        "darker by that many stops), auto (per picture: its brightest 1% at 0.8) or a factor on the "
        "linear radiance (the 'exposure' render.json states, to match another render). The EXRs are "
        "linear whatever the exposure.",
    ),
    size: tuple[int, int] = typer.Option((320, 240), "--size", help="Image width and height in pixels."),
    reference: bool = typer.Option(
        False, "--reference", help="Also path-trace the reference (Mitsuba volpath) and compare."
    ),
    spp: int = typer.Option(32, "--spp", help="Samples per pixel of each of the two reference renders."),
    radius: float = typer.Option(
        None,
        "--radius",
        help="Near radius of the transport, mm: pairs within it summed exactly, those beyond it through the "
        "hierarchical far field (default: the 99% energy radius, or less where the pairs would not fit in a "
        "quarter of --max-memory or of the machine's memory). A smaller radius lowers the memory.",
    ),
    incidence: str = typer.Option(
        "half-space",
        "--incidence",
        metavar="LAW",
        help="How light arriving at an angle counts against the data's normal-incidence beams: 'half-space' "
        "(Chandrasekhar's plane albedo per vertex from its measured total: oblique light comes back more, "
        "and by reciprocity leaves more toward oblique views; index-matched objects), 'half-space-in' (the "
        "light in only, a Lambertian exit) or 'normal' (every direction as measured).",
    ),
    through: bool = typer.Option(
        False,
        "--through",
        help="Use the model's through-body table (light between sides whose normals face apart, measured "
        "against the fit): brighter back-lit objects, not better on every case (docs/objects.md).",
    ),
    scene: Path = typer.Option(
        None,
        "--scene",
        help="A Mitsuba 3 scene file (XML) to render the fitted objects in: its emitters, shapes, sensor "
        "and film as they are; name the objects with --model (docs/objects.md, 'Your scene').",
    ),
    models: list[str] = typer.Option(
        [],
        "--model",
        metavar="ID=FILE",
        help="With --scene: the shape with this id is this per-vertex model (its mesh from 'translucency "
        "export MODEL --ply', placed by to_world). Repeat for several objects.",
    ),
    scene_unit: float = typer.Option(1.0, "--scene-unit", help="With --scene: millimetres per scene unit."),
    samples: int = typer.Option(
        32, "--samples", help="With --scene: irradiance samples per vertex and pass (path-traced)."
    ),
    passes: int = typer.Option(
        2,
        "--passes",
        help="With --scene: light-in / through-the-body passes (2: the scene lit by the objects "
        "lights them back once).",
    ),
    max_depth: int = typer.Option(8, "--max-depth", help="With --scene: longest light path, bounces."),
    roughness: float = typer.Option(
        0.0, "--roughness", help="With --scene: GGX roughness of a dielectric object's boundary (0: smooth)."
    ),
    picture_spp: int = typer.Option(
        16, "--picture-spp", help="With --scene: samples per pixel of our picture."
    ),
    overwrite: bool = overwrite_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Relight a fitted object: irradiance per vertex, sparse transport, a picture through Mitsuba (EXR + PNG)."""  # noqa: E501 — Typer lists the docstring verbatim as the command's one-line help; a line break would show in `translucency --help`
    from ..render import MAX_PAIRS, default_radius  # heavy: Mitsuba, Numba, trimesh load only to render
    from ..render.camera import Camera, view_direction
    from ..render.figure import figure2
    from ..render.lights import Placement, parse_light, place_light
    from ..render.object import boundary_eta, check_light_outside, object_of_model, volume_of_dataset
    from ..render.reference import check_reference
    from ..render.tonemap import parse_exposure

    check_option("--spp", spp, lo=1)
    from ..model.incidence import INCIDENCE_LAWS  # numpy only

    if incidence not in INCIDENCE_LAWS:
        raise TranslucencyError(f"--incidence: {incidence!r} is not one of {', '.join(INCIDENCE_LAWS)}")
    if scene is not None:
        if model is not None:
            raise TranslucencyError(f"{model}: with --scene, name the objects with --model ID=FILE instead")
        given = [
            f
            for f, v, d in (
                ("--light", light, [DEFAULT_LIGHT]),
                ("--view", view, "1,-1.6,0.7"),
                ("--size", tuple(size), (320, 240)),
                ("--through", through, False),
            )
            if v != d
        ]
        if given:
            raise TranslucencyError(
                f"{given[0]}: the scene file says this (its emitters, sensor and film); not with --scene"
            )
        return render_scene(
            scene=scene,
            models=models,
            out=out,
            scene_unit=scene_unit,
            samples=samples,
            passes=passes,
            max_depth=max_depth,
            roughness=roughness,
            picture_spp=picture_spp,
            incidence=incidence,
            radius=radius,
            exposure=exposure,
            reference=reference,
            spp=spp,
            overwrite=overwrite,
            max_memory=max_memory,
            quiet=quiet,
            as_json=as_json,
        )
    if models:
        raise TranslucencyError("--model: names the objects of a --scene; give the scene file too")
    if model is None:
        raise TranslucencyError("render: give a per-vertex model file, or --scene SCENE.xml --model ID=FILE")
    chosen_exposure = parse_exposure(exposure, name="--exposure")
    relative = [parse_light(t) for t in light]  # the text checked; placed once the object is known
    if len(relative) > 1:
        raise TranslucencyError("--light: one light per render for now (run once per light)")
    check_option("--radius", radius, lo=1e-6, hi=1e9)  # 1 nm to 1000 km (the far field divides by r²)
    for value in size:
        check_option("--size", value, lo=1, hi=16384)
    run = Run("render", max_memory=max_memory, quiet=quiet)
    # the options first (no file read), then the model and what it implies, then the output, then work
    direction = view_direction(view, "--view")
    expect_input(model, ("model file",))  # a data set or a mesh file where the model belongs: say so
    m = load_model(model)
    header = read_header(model)
    if m.geometry != "mesh":
        raise TranslucencyError(
            f"{model}: a planar model; render needs a per-vertex model of a mesh data set"
        )
    mesh, dheader = object_of_model(m, header)
    placement = Placement.of(mesh, direction)
    lights = [place_light(lit, placement) for lit in relative]
    check_light_outside(mesh, lights[0])
    if reference:  # a light volpath cannot render, a filling gone or changed: one line, before any work
        check_reference(lights[0], boundary_eta(dheader))
    vol = volume_of_dataset(mesh, dheader) if reference else None
    V = len(mesh.vertices)
    # the default radius: the model's 99 % energy radius, at most what a share of the memory holds
    budget = resources.memory.transport_budget(run.limit)
    rad = default_radius(m, mesh, max_pairs=min(MAX_PAIRS, 2 * budget)) if radius is None else float(radius)
    picture = dict(
        vertices=V,
        surface_mm2=float(mesh.area),
        radius_mm=rad,
        width=size[0],
        height=size[1],
        reference=reference,
        spp_reference=spp,
        max_pairs=MAX_PAIRS,
    )
    need = run.check(resources.memory.rendering(**picture), out)
    run.claim_folder(out, overwrite=overwrite, inputs=[model, header.get("meta", {}).get("dataset") or None])
    timing = run.time(resources.timing.rendering_units(**picture))
    what, _, flags = need.what.partition(": ")  # "the transport: --radius"
    run.info(
        f"render of {V:,} vertices at {size[0]} x {size[1]}, transport radius {rad:.3g} mm; time "
        f"{timing.text()}, memory ~{need.memory / 2**30:.2g} GiB (mostly {what}"
        f"{f'; a smaller {flags} lowers it' if flags else ''})"
    )
    run.info(f"{placement.describe()}; light {lights[0]!r}")
    cam = Camera.looking_at(mesh, direction, *size)
    steps = 4 if reference else 3
    with run.work("render", total=steps) as work:
        res = figure2(
            m,
            mesh,
            lights[0],
            out,
            volume=vol,
            camera=cam,
            spp_reference=spp,
            radius=rad,
            eta=boundary_eta(dheader),
            exposure=chosen_exposure,
            incidence=incidence,
            through=through,
            progress=lambda done, total, name: work.update(completed=done, total=total, item=name),
        )
        work.update(completed=steps, item="done")
        work.fresh = not res.get("reference_cached", False)
    table = Table(title=f"render of {model.name}", show_header=False)
    for k, v in res.items():
        table.add_row(k, f"{v:.4g}" if isinstance(v, float) else str(v))
    summary = {"command": "render", "model": model, "images": out, **res, "light": _light_record(lights[0])}
    run.finish(as_json, summary, [table, f"images: {out}"])


def _light_record(light) -> dict:
    """A light as JSON: its kind (point, directional, spot, environment) and its parameters."""
    return light.record()
