"""Rendering fitted objects in a user's Mitsuba 3 scene as one function (:func:`render_scene`), with the
scene path-traced with the objects' volumes in place and their comparison on request.

``translucency render scene`` is this function: the arguments checked at the boundary, the scene and its
objects read (each a :class:`~translucency.transport.PreparedObject` placed by the scene's shape), the
memory and time estimated before the work (refused in one line beyond ``max_memory``), the pictures (EXR
linear, PNG tone-mapped) and the numbers.  Units: a scene in other units than mm says how many mm one of
its units is; radiance in W/(mm² sr) per the scene's light, linear RGB.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from .. import resources
from .._validate import TranslucencyError, check_option
from ..io.atomic import write_json
from ..io.records import jsonable
from ..model.lean import has_lean
from ..render.compare import FLIP_SKIPPED, flip_available
from ..render.still import plot_comparison
from ..render.tonemap import auto_exposure, parse_exposure, save_images, tonemap
from ..resources.memory import transport_pairs
from ..resources.run import Reporter, Run
from ..scene import FittedScene
from ..scene.compare import lit_pixels, object_pixels, scene_errors
from ..scene.irradiance import samples_per_wavefront
from ..scene.reference import converged_scene_reference
from ..transport import TransportOptions

__all__ = ["SceneRendering", "render_scene"]


@dataclasses.dataclass
class SceneRendering:
    """What :func:`render_scene` made: our picture, the reference (if asked for), the folder, the summary.

    Examples
    --------
    The example scene around the example model (its shape ``object`` reads ``object.ply``, written beside
    it), lit quickly with few samples:

    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> folder, model = Path(tempfile.mkdtemp()), tl.data.example_path("spot_coarse.model.zip")
    >>> _ = tl.copy_examples(folder), tl.export_ply(model, folder / "object.ply")
    >>> shot = tl.render_scene(folder / "scene.xml", {"object": model}, folder / "shot", samples=4, passes=1,
    ...                        picture_spp=2)
    >>> shot.picture.shape, shot.reference is None, (shot.folder / "scene.json").is_file()
    ((240, 320, 3), True, True)
    """

    picture: np.ndarray  # (H, W, 3) linear radiance of the scene with the fitted objects glowing in it
    reference: np.ndarray | None  # (H, W, 3) Mitsuba volpath with the objects' volumes in place, or None
    folder: Path  # ours.exr/.png, reference.exr/.png, scene.png, scene.json
    summary: dict  # scene.json and ``translucency render scene --json``


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
    radius: float | None = None,
    exposure: str = "fixed",
    reference: bool = False,
    spp: int = 32,
    angles: bool = False,
    paper: bool = False,
    transport: TransportOptions | None = None,
    overwrite: bool = False,
    max_memory: str | int | None = None,
    reporter: Reporter | None = None,
) -> SceneRendering:
    """Fitted objects in a user's Mitsuba 3 scene: prepared, lit (light in, through the body), drawn
    through the scene's camera; with ``reference`` the scene path-traced with the volumes in place.

    ``translucency render scene SCENE --object ID=FILE`` is this function.

    Parameters
    ----------
    scene : path
        A Mitsuba 3 scene file (XML): its emitters, shapes, sensor and film as they are.
    objects : dict of str to path
        Shape id of the scene → per-vertex model file (its mesh from ``translucency export --ply``).
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
    radius, exposure, reference, spp, paper, transport, overwrite, max_memory, reporter
        As in :func:`~translucency.workflow.rendering.render_model` (``radius``: one near radius for every
        object; default each model's own).

    Returns
    -------
    SceneRendering

    Examples
    --------
    The example scene (:func:`translucency.copy_examples`) with the example model in its shape ``object``;
    the scene reads the shape's mesh from ``object.ply``, which :func:`translucency.export_ply` writes:

    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> folder, model = Path(tempfile.mkdtemp()), tl.data.example_path("spot_coarse.model.zip")
    >>> _ = tl.copy_examples(folder), tl.export_ply(model, folder / "object.ply")
    >>> shot = tl.render_scene(folder / "scene.xml", {"object": model}, folder / "shot", samples=4, passes=1,
    ...                        picture_spp=2)
    >>> shot.summary["objects"]["object"]["vertices"], sorted(p.name for p in shot.folder.glob("ours.*"))
    (402, ['ours.exr', 'ours.png'])

    The defaults (32 irradiance samples a vertex, two passes, 16 samples a pixel) take longer and are less
    noisy; ``reference=True`` path-traces the scene with the object's filling in place.
    """
    for name, value in (("samples", samples), ("passes", passes), ("max_depth", max_depth),
                        ("picture_spp", picture_spp), ("spp", spp)):  # fmt: skip
        check_option(name, value, lo=1)
    check_option("scene_unit", scene_unit, lo=1e-9, hi=1e12)
    check_option("roughness", roughness, lo=0.0, hi=1.0)
    chosen = parse_exposure(exposure, name="exposure")
    options = TransportOptions.of(transport, paper=paper, angles=angles, radius=radius)
    scene, out = Path(scene), Path(out)
    pairs = {str(k): Path(v) for k, v in objects.items()}
    if not pairs:
        raise TranslucencyError("objects: name the fitted objects (shape id = model file)")
    run = Run("render", max_memory=max_memory, reporter=reporter, timer="render scene")
    t = time.perf_counter()
    # the scene, the models and their places first (one line for each mistake), then the estimates
    fs = FittedScene(
        scene, pairs, scene_unit_mm=scene_unit, roughness=roughness, samples=samples, passes=passes,
        max_depth=max_depth, transport=options,
    )  # fmt: skip
    _notes(run, fs, reference)
    run.claim_folder(_estimated(run, fs, out, reference, spp, picture_spp), overwrite=overwrite,
                     inputs=[scene, *pairs.values()])  # fmt: skip
    with run.work("render", total=5 if reference else 4) as work:
        ours, ref, summary = _drawn(fs, work, (scene, pairs, out), chosen, reference, spp, picture_spp)
    summary["seconds"] = time.perf_counter() - t
    write_json(out / "scene.json", jsonable(summary))
    return SceneRendering(ours, ref, out, run.summary(summary))


def _drawn(fs: FittedScene, work, files: tuple, chosen, reference: bool, spp: int, picture_spp: int):
    """The render's steps, each told to ``work``: the transports, the light, our picture, the masks, and
    with ``reference`` the path-traced reference and the comparison; the pictures written into the output
    folder.  Returns (ours, the reference or None, the summary)."""
    scene, pairs, out = files
    step = lambda k, name: work.update(completed=k, item=name)  # noqa: E731 — one line per step
    step(0, "transport (once per object)")
    fs.prepare()  # each object at the radius its prepared object chose (a default one shrinks if it must)
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
    summary = _summary(fs, scene, pairs, out, (t_light, t_draw), picture_spp, objects)
    auto = auto_exposure(ours, measured)
    scale = auto if chosen.rule != "scale" else float(chosen.scale)
    ref = None
    if reference:
        step(4, "volpath reference (2 renders)")
        ref = _compared(fs, ours, objects, measured, spp, picture_spp, t_light + t_draw, summary)
        save_images(ref, out / "reference", scale)
        _plot(tonemap(ref, scale), tonemap(ours, scale), summary.pop("flip_map"), objects,
              summary["errors"], out / "scene.png")  # fmt: skip
    save_images(ours, out / "ours", scale)
    summary["exposure"] = scale
    work.update(completed=5 if reference else 4, item="done")
    return ours, ref, summary


def _notes(run, fs: FittedScene, reference: bool) -> None:
    """One line for each thing of the user's scene that is replaced, and each thing drawn otherwise than
    asked (no FLIP, an object without a lean)."""
    for note in fs.notes:
        run.info(note)
    if reference and not flip_available():  # the comparison goes on with the relative RMSE
        run.info(FLIP_SKIPPED)
    if fs.transport.angles:  # one line for each object drawn without a lean
        for o in fs.objects:
            if not has_lean(o.model):
                run.info(f"--angles: {o.name}'s model has no lean (fit data acquired with --incidence)")


def _estimated(run, fs: FittedScene, out: Path, reference: bool, spp: int, picture_spp: int) -> Path:
    """The memory (refused beyond the limit) and the time of the render, checked and stated before any
    work; returns the output folder."""
    W, H = fs.film_size
    pairs_total = sum(
        transport_pairs(
            vertices=len(o.mesh.vertices),
            surface_mm2=float(o.mesh.area),
            radius_mm=o.prepared.radius,
            max_pairs=o.prepared.options.max_pairs,
        )
        for o in fs.objects
    )
    # the irradiance's largest wavefront, as traced
    paths = max(
        len(o.mesh.vertices) * samples_per_wavefront(len(o.mesh.vertices), fs.samples) for o in fs.objects
    )
    need = run.check(
        resources.memory.scene_rendering(
            pairs=pairs_total, paths=paths, vertices=fs.vertices, pixels=W * H, spp=picture_spp,
            reference=reference, spp_reference=spp,
        ),
        out,
    )  # fmt: skip
    units = {
        "vertices": fs.vertices,
        "pairs": pairs_total,
        "paths": fs.vertices * (fs.samples + (fs.passes - 1) * fs.glow_samples),
        "samples": W * H * picture_spp,
        "reference_samples": 2 * 3 * W * H * spp if reference else 0,
    }
    timing = run.time(units)
    run.info(
        f"{len(fs.objects)} fitted object(s), {fs.vertices:,} vertices, a {W} x {H} picture; time "
        f"{timing.text()}, memory ~{need.memory / 2**30:.2g} GiB"
    )
    return out


def _summary(fs: FittedScene, scene: Path, pairs: dict, out: Path, times: tuple, picture_spp: int, objects):
    """scene.json's numbers before the comparison: the objects as drawn, the times, the pixels."""
    return {
        "command": "render",
        "scene": scene,
        "models": {k: str(v) for k, v in pairs.items()},
        "images": out,
        "objects": {
            o.name: {
                "vertices": len(o.mesh.vertices),
                "eta": o.eta,
                "incidence": o.law.name,
                "angles": o.prepared.has_lean,
                "through": bool(o.transport.through),
            }
            for o in fs.objects
        },
        "prepare_s": fs.prepare_s,
        "radius_mm": [o.prepared.radius for o in fs.objects],
        "light_s": times[0],
        "draw_s": times[1],
        "passes": fs.passes,
        "samples": fs.samples,
        "picture_spp": picture_spp,
        "object_pixels": int(objects.sum()),
    }


def _compared(fs, ours, objects, measured, spp: int, picture_spp: int, ours_s: float, summary: dict):
    """The scene path-traced with the volumes in place, compared with ours over the objects and over what
    they light (into ``summary``: ``errors``, the reference's noise, samples and time, and ``flip_map``);
    returns the reference."""
    dark = fs.render(spp=picture_spp, glowing=False)
    ref, info = converged_scene_reference(fs, measured, spp=spp)
    errors = scene_errors(ref, ours, objects, lit_pixels(ours, dark, objects))
    summary["flip_map"] = errors.pop("flip_map")
    summary.update(
        errors=errors,
        reference_noise=info["noise"],
        reference_spp=spp,
        reference_s=info["seconds"],
        speedup_vs_reference=info["seconds"] / max(ours_s, 1e-9),
    )
    return ref


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
