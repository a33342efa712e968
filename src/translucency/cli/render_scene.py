"""The scene branch of ``translucency render``: fitted objects in a user's Mitsuba scene (``--scene`` with
``--model ID=FILE``), our picture through the scene's camera, and with ``--reference`` the scene
path-traced with the objects' volumes in place and the comparison."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from rich.table import Table

from .. import resources
from .._validate import TranslucencyError, check_option
from ..io.atomic import write_json
from ._common import jsonable
from ._run import Run


def parse_models(texts: list[str]) -> dict[str, Path]:
    """``ID=FILE`` pairs (``--model``) as {id: path}; one line for a malformed or repeated one."""
    out: dict[str, Path] = {}
    for text in texts:
        key, eq, path = text.partition("=")
        if not eq or not key.strip() or not path.strip():
            raise TranslucencyError(
                f"--model {text!r}: expected ID=FILE (a shape id of the scene = a model file)"
            )
        if key.strip() in out:
            raise TranslucencyError(f"--model: the shape id {key.strip()!r} is given twice")
        out[key.strip()] = Path(path.strip())
    if not out:
        raise TranslucencyError(
            "--scene: name the fitted objects with --model ID=FILE (shape id = model file)"
        )
    return out


def render_scene(
    *,
    scene: Path,
    models: list[str],
    out: Path,
    scene_unit: float,
    samples: int,
    passes: int,
    max_depth: int,
    roughness: float,
    picture_spp: int,
    incidence: str,
    radius: float | None,
    exposure: str,
    reference: bool,
    spp: int,
    overwrite: bool,
    max_memory: str,
    quiet: bool,
    as_json: bool,
) -> None:
    """``render --scene``: prepare, light (two passes), draw, and with ``reference`` compare."""
    from ..render import MAX_PAIRS, default_radius  # heavy: Mitsuba, Numba, trimesh load only to render
    from ..render.tonemap import auto_exposure, parse_exposure, save_images, tonemap  # Mitsuba loads
    from ..resources.memory import transport_pairs
    from ..scene import FittedScene
    from ..scene.compare import lit_pixels, object_pixels, scene_errors
    from ..scene.reference import converged_scene_reference

    pairs = parse_models(models)
    for option, value, lo in (
        ("--samples", samples, 1),
        ("--passes", passes, 1),
        ("--max-depth", max_depth, 1),
        ("--picture-spp", picture_spp, 1),
        ("--spp", spp, 1),
    ):
        check_option(option, value, lo=lo)
    check_option("--scene-unit", scene_unit, lo=1e-9, hi=1e12)
    check_option("--roughness", roughness, lo=0.0, hi=1.0)
    chosen = parse_exposure(exposure, name="--exposure")
    if radius is not None:
        check_option("--radius", radius, lo=1e-6, hi=1e9)
    run = Run("render", max_memory=max_memory, quiet=quiet, timer="render scene")
    t = time.perf_counter()
    # the scene, the models and their places first (one line for each mistake), then the estimates
    fs = FittedScene(
        scene,
        pairs,
        scene_unit_mm=scene_unit,
        incidence=incidence,
        roughness=roughness,
        samples=samples,
        passes=passes,
        max_depth=max_depth,
    )
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
    paths = fs.vertices * samples
    need = run.check(
        resources.memory.scene_rendering(
            pairs=pairs_total,
            paths=paths,
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
        "paths": paths * passes,
        "samples": W * H * picture_spp,
        "reference_samples": 2 * 3 * W * H * spp if reference else 0,
    }
    timing = run.time(units)
    run.info(
        f"{len(fs.objects)} fitted object(s), {fs.vertices:,} vertices, a {W} x {H} picture; time "
        f"{timing.text()}, memory ~{need.memory / 2**30:.2g} GiB"
    )
    with run.work("render", total=5 if reference else 4) as work:
        step = lambda k, name: work.update(completed=k, item=name)  # noqa: E731 — one line per step
        step(0, "transport (once per object)")
        fs.prepare(radii)  # the radii the estimates were made with
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
                o.name: {"vertices": len(o.mesh.vertices), "eta": o.eta, "incidence": o.law.name}
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
    run.finish(as_json, summary, [table, f"images: {out}"])


def _plot(ref_ldr, our_ldr, flip_map, objects, errors, path) -> None:
    """reference | ours | FLIP over the objects into ``path``."""
    from ..render.figure import plot_comparison  # Matplotlib only for the figure

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
