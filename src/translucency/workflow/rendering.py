"""Rendering as one function: a fitted object relit (:func:`render_model`), or fitted objects in a user's
Mitsuba scene (:func:`render_scene`), each with the path-traced reference and their comparison on request.

``translucency render`` is these functions: the arguments checked at the boundary, the model and the
light placed, the memory and time estimated before the work (refused in one line beyond ``max_memory``),
the pictures (EXR linear, PNG tone-mapped) and the numbers.  Units: mm (a scene in other units says how
many mm one of its units is), radiance in W/(mm² sr), linear RGB.
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from .. import resources
from .._validate import TranslucencyError, check_option
from ..io.atomic import write_json
from ..io.inputs import expect_input
from ..io.records import jsonable
from ..io.vertex_model import check_vertex_model
from ..model.incidence import INCIDENCE_LAWS
from ..model.lean import NO_LEAN, has_lean
from ..render import MAX_PAIRS, Camera, default_radius, parse_light
from ..render.camera import view_direction
from ..render.compare import FLIP_SKIPPED, flip_available
from ..render.figure import figure2, plot_comparison
from ..render.lights import Placement, place_light
from ..render.object import boundary_eta, check_light_outside, object_of_model, volume_of_dataset
from ..render.reference import check_reference
from ..render.tonemap import auto_exposure, parse_exposure, save_images, tonemap
from ..resources.memory import transport_pairs
from ..resources.run import Reporter, Run
from ..rig.shared.hdr import read_hdr
from ..scene import FittedScene
from ..scene.compare import lit_pixels, object_pixels, scene_errors
from ..scene.irradiance import samples_per_wavefront
from ..scene.reference import converged_scene_reference
from ._arguments import model_and_record, whole_number

__all__ = ["DEFAULT_LIGHT", "Rendering", "SceneRendering", "render_model", "render_scene"]

#: the light of a render when none is given: above and in front of the default view, in mm
DEFAULT_LIGHT = "point:60,-80,120,2e4"


@dataclasses.dataclass
class Rendering:
    """What :func:`render_model` made: our picture, the reference (if asked for), the numbers, the folder.

    Examples
    --------
    >>> import translucency as tl
    >>> shot = tl.render_model("pig.model.zip", "render", reference=True)  # doctest: +SKIP
    >>> shot.picture.shape, shot.numbers["rel_rmse"] < 0.1  # doctest: +SKIP
    ((240, 320, 3), True)
    """

    picture: np.ndarray  # (H, W, 3) linear radiance, our model's
    reference: np.ndarray | None  # (H, W, 3) Mitsuba volpath of the filling, or None
    numbers: dict  # render.json: timings, and with a reference FLIP, relative RMSE, regions
    folder: Path | None  # where ours.exr/.png (and the reference, render.png) are; None: not kept
    summary: dict = dataclasses.field(default_factory=dict)  # ``translucency render --json``


def render_model(
    model,
    out=None,
    *,
    light=DEFAULT_LIGHT,
    view=(1.0, -1.6, 0.7),
    resolution=(320, 240),
    exposure: str = "fixed",
    reference: bool = False,
    spp: int = 32,
    radius: float | None = None,
    incidence_law: str = "half-space",
    paper: bool = False,
    angles: bool = False,
    overwrite: bool = False,
    max_memory: str | int | None = None,
    reporter: Reporter | None = None,
) -> Rendering:
    """Relight a fitted object under a light: irradiance per vertex, sparse transport, a Mitsuba picture.

    ``translucency render MODEL`` is this function.

    Parameters
    ----------
    model : FitResult, ReflectanceModel or path
        A per-vertex model (a fit on a mesh data set) that carries its mesh.
    out : str or Path, optional
        Folder for ``ours.exr/.png`` (and ``reference.exr/.png``, ``render.png``, ``render.json``);
        default: none kept, the pictures are only returned.
    light : str or Light
        In the object's frame, mm: ``point:x,y,z[,I]``, ``directional:dx,dy,dz[,E]``, ``spot:…``,
        ``env:L``, ``env:MAP.exr``, or relative to the object ``point@AZ,EL[,DIST[,I]]``, …
        (:func:`translucency.render.parse_light`), or a light object.
    view : (float, float, float) or str
        Direction from the object's centre towards the camera (the camera looks at the centre from 1.9
        object sizes).
    resolution : (int, int)
        Width and height in pixels (``size`` still works for one release, with a DeprecationWarning).
    exposure : str
        Of the PNGs: ``fixed``, ``fixed+STOPS``, ``auto`` or a factor on the linear radiance (the EXRs are
        linear whatever the exposure).
    reference : bool
        Also path-trace the reference (Mitsuba volpath of the filling) and compare.
    spp : int
        Samples per pixel of each of the reference's two renders.
    radius : float, optional
        Near radius of the transport, mm (default: the 99 % energy radius, or less where the pairs
        would not fit in a quarter of ``max_memory`` or of the machine's memory).
    incidence_law : {"half-space", "half-space-in", "normal"}
        How light arriving at an angle counts against the data's normal-incidence beams (``incidence``
        still works for one release, with a DeprecationWarning).
    paper : bool
        Draw the paper's model: each point's radial profile alone.  By default the model's through-body
        table (:mod:`translucency.model.through`) is drawn with it wherever the model holds one (every fit
        on a mesh); the summary's ``through`` says whether it was.
    angles : bool
        Lean the near transport toward the light's and the camera's directions (a model fitted from a
        data set with oblique beams, :mod:`translucency.model.lean`; a light of one direction per vertex);
        the summary's ``angles`` says whether it did.
    overwrite : bool
        Replace an earlier output folder of translucency at ``out`` (never anything else).
    max_memory : str or int, optional
        Most memory the render may use; a larger estimate is refused before any work.
    reporter : Reporter, optional
        Hears the run's information lines and progress (default: silent).

    Returns
    -------
    Rendering
        ``.picture``, ``.reference``, ``.numbers`` (render.json), ``.folder``, ``.summary``.

    Examples
    --------
    >>> import translucency as tl
    >>> pic = tl.render_model("pig_iso.model.zip", resolution=(160, 120))  # doctest: +SKIP
    >>> pic.picture.shape  # doctest: +SKIP
    (120, 160, 3)
    """
    if incidence_law not in INCIDENCE_LAWS:
        raise TranslucencyError(f"incidence_law: {incidence_law!r} is not one of {', '.join(INCIDENCE_LAWS)}")
    check_option("spp", whole_number("spp", spp), lo=1)
    check_option("radius", radius, lo=1e-6, hi=1e9)  # 1 nm to 1000 km (the far field divides by r²)
    size = tuple(whole_number("resolution", v) for v in np.atleast_1d(resolution))
    if len(size) != 2:
        raise TranslucencyError(f"resolution: expected (width, height), got {resolution!r}")
    for v in size:
        check_option("resolution", v, hi=16384)
    chosen_exposure = parse_exposure(exposure, name="exposure")
    relative = parse_light(light) if isinstance(light, str) else light  # placed once the object is known
    if not hasattr(relative, "place"):  # a light, or one placed relative to the object
        raise TranslucencyError(f"light: expected a light or its text (point:x,y,z,I …), got {light!r}")
    run = Run("render", max_memory=max_memory, reporter=reporter)
    # the arguments first (no file read), then the model and what it implies, then the output, then work
    direction = view_direction(view, "view")
    if isinstance(model, (str, os.PathLike)):
        expect_input(Path(model), ("model file",))  # a data set or a mesh file where the model belongs
    fitted, record = model_and_record("model", model)
    check_vertex_model(fitted, "render", model if isinstance(model, (str, os.PathLike)) else "model")
    mesh, acquisition = object_of_model(fitted, {"meta": record})
    placement = Placement.of(mesh, direction)
    lit = place_light(relative, placement)
    check_light_outside(mesh, lit)
    eta = boundary_eta(acquisition)
    if reference:  # a light volpath cannot render, a filling gone or changed: one line, before any work
        check_reference(lit, eta)
    volume = volume_of_dataset(mesh, acquisition) if reference else None
    V = len(mesh.vertices)
    # the default radius: the model's 99 % energy radius, at most what a share of the memory holds
    budget = resources.memory.transport_budget(run.limit)
    rad = (
        default_radius(fitted, mesh, max_pairs=min(MAX_PAIRS, 2 * budget))
        if radius is None
        else float(radius)
    )
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
    inputs = [model, record.get("dataset") or None] if isinstance(model, (str, os.PathLike)) else []
    with tempfile.TemporaryDirectory(prefix="translucency-render-") as scratch:
        folder = Path(scratch) if out is None else Path(out)
        need = run.check(resources.memory.rendering(**picture), None if out is None else folder)
        if out is not None:
            run.claim_folder(folder, overwrite=overwrite, inputs=inputs)
        timing = run.time(resources.timing.rendering_units(**picture))
        what, _, flags = need.what.partition(": ")  # "the transport: --radius"
        run.info(
            f"render of {V:,} vertices at {size[0]} x {size[1]}, transport radius {rad:.3g} mm; time "
            f"{timing.text()}, memory ~{need.memory / 2**30:.2g} GiB (mostly {what}"
            f"{f'; a smaller {flags} lowers it' if flags else ''})"
        )
        run.info(f"{placement.describe()}; light {lit!r}")
        if reference and not flip_available():  # the comparison goes on with the relative RMSE
            run.info(FLIP_SKIPPED)
        if angles and not has_lean(fitted):  # one line: what is drawn instead
            run.info(NO_LEAN)
        elif angles and not lit.delta:
            run.info("--angles: a light of many directions leans by its irradiance-weighted mean direction")
        camera = Camera.looking_at(mesh, direction, *size)
        steps = 4 if reference else 3
        with run.work("render", total=steps) as work:
            numbers = figure2(
                fitted,
                mesh,
                lit,
                folder,
                volume=volume,
                camera=camera,
                spp_reference=spp,
                radius=None if radius is None else rad,  # (the default: rad, shrunk if its pairs crowd)
                max_pairs=min(MAX_PAIRS, 2 * budget),
                eta=eta,
                exposure=chosen_exposure,
                incidence=incidence_law,
                through=False if paper else None,
                angles=angles,
                progress=work.step(),
            )
            work.update(completed=steps, item="done")
            work.fresh = not numbers.get("reference_cached", False)
        ours = read_hdr(folder / "ours.exr")
        ref = read_hdr(folder / "reference.exr") if reference else None
    summary = {"command": "render", "model": model, "images": out, **numbers, "light": lit.record()}
    return Rendering(ours, ref, numbers, None if out is None else folder, run.summary(summary))


@dataclasses.dataclass
class SceneRendering:
    """What :func:`render_scene` made: our picture, the reference (if asked for), the folder, the summary.

    Examples
    --------
    >>> import translucency as tl
    >>> shot = tl.render_scene("scene.xml", {"pig": "pig.model.zip"}, "shot")  # doctest: +SKIP
    >>> (shot.folder / "scene.json").is_file()  # doctest: +SKIP
    True
    """

    picture: np.ndarray  # (H, W, 3) linear radiance of the scene with the fitted objects glowing in it
    reference: np.ndarray | None  # (H, W, 3) Mitsuba volpath with the objects' volumes in place, or None
    folder: Path  # ours.exr/.png, reference.exr/.png, scene.png, scene.json
    summary: dict  # scene.json and ``translucency render --scene --json``


def render_scene(
    scene,
    objects: dict,
    out,
    *,
    scene_unit: float = 1.0,
    samples: int = 32,
    passes: int = 2,
    max_depth: int = 8,
    roughness: float = 0.0,
    picture_spp: int = 16,
    incidence_law: str = "half-space",
    radius: float | None = None,
    exposure: str = "fixed",
    reference: bool = False,
    spp: int = 32,
    angles: bool = False,
    paper: bool = False,
    overwrite: bool = False,
    max_memory: str | int | None = None,
    reporter: Reporter | None = None,
) -> SceneRendering:
    """Fitted objects in a user's Mitsuba 3 scene: prepared, lit (light in, through the body), drawn
    through the scene's camera; with ``reference`` the scene path-traced with the volumes in place.

    ``translucency render --scene SCENE --object ID=FILE`` is this function.

    Parameters
    ----------
    scene : path
        A Mitsuba 3 scene file (XML): its emitters, shapes, sensor and film as they are.
    objects : dict of str to path
        Shape id of the scene → per-vertex model file (its mesh from ``translucency export --ply``;
        ``models`` still works for one release, with a DeprecationWarning).
    out : str or Path
        Folder for ``ours.exr/.png``, ``scene.json`` (and ``reference.exr/.png``, ``scene.png``).
    scene_unit : float
        Millimetres per scene unit.
    samples, passes, max_depth : int
        Irradiance samples per vertex of the first pass (a later one, the objects' glow alone, takes a
        quarter), light-in / through-the-body passes, longest light path.
    roughness : float
        GGX roughness of a dielectric object's boundary (0: smooth).
    picture_spp : int
        Samples per pixel of our picture.
    angles : bool
        Objects whose model has a lean lean toward the scene's light, by its irradiance-weighted mean
        lean vector per vertex (the summary's ``angles`` per object says whether it did).
    incidence_law, radius, exposure, reference, spp, paper, overwrite, max_memory, reporter
        As in :func:`render_model`.

    Returns
    -------
    SceneRendering

    Examples
    --------
    >>> import translucency as tl
    >>> shot = tl.render_scene("scene.xml", {"pig": "pig.model.zip"}, "shot")  # doctest: +SKIP
    >>> shot.summary["objects"]["pig"]["vertices"]  # doctest: +SKIP
    27012
    """
    if incidence_law not in INCIDENCE_LAWS:
        raise TranslucencyError(f"incidence_law: {incidence_law!r} is not one of {', '.join(INCIDENCE_LAWS)}")
    for name, value in (
        ("samples", samples),
        ("passes", passes),
        ("max_depth", max_depth),
        ("picture_spp", picture_spp),
        ("spp", spp),
    ):
        check_option(name, value, lo=1)
    check_option("scene_unit", scene_unit, lo=1e-9, hi=1e12)
    check_option("roughness", roughness, lo=0.0, hi=1.0)
    chosen = parse_exposure(exposure, name="exposure")
    check_option("radius", radius, lo=1e-6, hi=1e9)
    scene, out = Path(scene), Path(out)
    pairs = {str(k): Path(v) for k, v in objects.items()}
    if not pairs:
        raise TranslucencyError("objects: name the fitted objects (shape id = model file)")
    run = Run("render", max_memory=max_memory, reporter=reporter, timer="render scene")
    t = time.perf_counter()
    # the scene, the models and their places first (one line for each mistake), then the estimates
    fs = FittedScene(
        scene,
        pairs,
        scene_unit_mm=scene_unit,
        incidence=incidence_law,
        roughness=roughness,
        samples=samples,
        passes=passes,
        max_depth=max_depth,
        angles=angles,
        through=False if paper else None,
    )
    for note in fs.notes:
        run.info(note)
    if reference and not flip_available():  # the comparison goes on with the relative RMSE
        run.info(FLIP_SKIPPED)
    if angles:  # one line for each object drawn without a lean
        for o in fs.objects:
            if not has_lean(o.model):
                run.info(f"--angles: {o.name}'s model has no lean (fit data acquired with --incidence)")
    W, H = fs.film_size
    radii = [
        default_radius(o.model, o.mesh, max_pairs=MAX_PAIRS) if radius is None else radius for o in fs.objects
    ]
    pairs_total = sum(
        transport_pairs(
            vertices=len(o.mesh.vertices), surface_mm2=float(o.mesh.area), radius_mm=r, max_pairs=MAX_PAIRS
        )
        for o, r in zip(fs.objects, radii)
    )
    # the irradiance's largest wavefront, as traced
    sizes = [len(o.mesh.vertices) for o in fs.objects]
    paths = max(V * samples_per_wavefront(V, samples) for V in sizes)
    need = run.check(
        resources.memory.scene_rendering(
            pairs=pairs_total,
            paths=paths,
            vertices=fs.vertices,
            pixels=W * H,
            spp=picture_spp,
            reference=reference,
            spp_reference=spp,
        ),
        out,
    )
    run.claim_folder(out, overwrite=overwrite, inputs=[scene, *pairs.values()])
    units = {
        "vertices": fs.vertices,
        "pairs": pairs_total,
        "paths": fs.vertices * (samples + (passes - 1) * fs.glow_samples),
        "samples": W * H * picture_spp,
        "reference_samples": 2 * 3 * W * H * spp if reference else 0,
    }
    timing = run.time(units)
    run.info(
        f"{len(fs.objects)} fitted object(s), {fs.vertices:,} vertices, a {W} x {H} picture; time "
        f"{timing.text()}, memory ~{need.memory / 2**30:.2g} GiB"
    )
    ref = None
    with run.work("render", total=5 if reference else 4) as work:
        step = lambda k, name: work.update(completed=k, item=name)  # noqa: E731 — one line per step
        step(0, "transport (once per object)")
        fs.prepare(radius)  # the radii the estimates were made with (a default one shrinks if it must)
        step(1, "light in, through the body")
        t1 = time.perf_counter()
        fs.light()
        t_light = time.perf_counter() - t1
        step(2, "picture")
        t1 = time.perf_counter()
        ours = fs.render(spp=picture_spp)
        t_draw = time.perf_counter() - t1
        step(3, "comparison masks")
        objects = object_pixels(fs)
        measured = objects if objects.any() else np.ones(objects.shape, bool)  # the pixels judged
        summary = {
            "command": "render",
            "scene": scene,
            "models": {k: str(v) for k, v in pairs.items()},
            "images": out,
            "objects": {
                o.name: {
                    "vertices": len(o.mesh.vertices),
                    "eta": o.eta,
                    "incidence": o.law.name,
                    "angles": bool(angles and o.transport.lean is not None),
                    "through": bool(o.transport.through),
                }
                for o in fs.objects
            },
            "prepare_s": fs.prepare_s,
            "radius_mm": radii,
            "light_s": t_light,
            "draw_s": t_draw,
            "passes": passes,
            "samples": samples,
            "picture_spp": picture_spp,
            "object_pixels": int(objects.sum()),
        }
        auto = auto_exposure(ours, measured)
        scale = auto if chosen.rule != "scale" else float(chosen.scale)
        if reference:
            step(4, "volpath reference (2 renders)")
            dark = fs.render(spp=picture_spp, glowing=False)
            ref, info = converged_scene_reference(fs, measured, spp=spp)
            errors = scene_errors(ref, ours, objects, lit_pixels(ours, dark, objects))
            flip_map = errors.pop("flip_map")
            summary.update(
                errors=errors,
                reference_noise=info["noise"],
                reference_spp=spp,
                reference_s=info["seconds"],
                speedup_vs_reference=info["seconds"] / max(t_light + t_draw, 1e-9),
            )
            save_images(ref, out / "reference", scale)
            _plot(tonemap(ref, scale), tonemap(ours, scale), flip_map, objects, errors, out / "scene.png")
        save_images(ours, out / "ours", scale)
        summary["exposure"] = scale
        work.update(completed=5 if reference else 4, item="done")
    summary["seconds"] = time.perf_counter() - t
    write_json(out / "scene.json", jsonable(summary))
    return SceneRendering(ours, ref, out, run.summary(summary))


def _plot(ref_ldr, our_ldr, flip_map, objects, errors, path) -> None:
    """reference | ours | FLIP over the objects into ``path``."""
    shown = np.where(objects, flip_map, np.nan) if flip_map is not None else np.zeros(objects.shape)
    o, lit = errors["object"], errors["lit"]
    lit_text = f"; lit by it {lit['rel_rmse']:.2f}" if lit.get("pixels") else ""
    flip, rmse = o.get("flip", float("nan")), o.get("rel_rmse", float("nan"))
    titles = (
        "reference: Mitsuba volpath, the volumes in the scene",
        "ours: fitted models glowing in the scene",
        f"FLIP over the objects {flip:.3f}; rel. RMSE {rmse:.2f}{lit_text}",
    )
    plot_comparison(ref_ldr, our_ldr, shown, path, titles)
