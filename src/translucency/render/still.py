"""One still of a fitted object, with its path-traced reference on request (the paper's Figure 2 is one).

:func:`render_still` lights a :class:`~translucency.transport.PreparedObject` (the transport every
renderer draws), draws it through one camera (:mod:`.camera`, :mod:`.picture`), and with a volume renders
the ``volpath`` reference (:mod:`.reference`), compares them (:mod:`.compare`) and writes
reference | ours | FLIP error with the numbers.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from .._plotting import pyplot
from ..io.atomic import atomic_path, write_json
from .camera import Camera
from .compare import compare, region_errors
from .lights import DEFAULT_DISTANCE, Placement
from .picture import VertexPicture, coverage
from .reference import converged_reference
from .tonemap import Exposure, auto_exposure, parse_exposure, save_images, tonemap


def render_still(
    prepared,
    light,
    out_dir,
    *,
    volume=None,
    camera: Camera | None = None,
    spp_reference: int = 32,
    spp: int = 16,
    reference_cache=True,
    progress=None,
    exposure: Exposure | str = "fixed",
    name: str = "render",
) -> dict:
    """Draw ``prepared`` under ``light``; with ``volume`` also the reference and the comparison.

    ``prepared``: a :class:`~translucency.transport.PreparedObject` (the model, its mesh, its boundary η
    and the transport's options: what is drawn, its docstring says).
    ``spp``: samples per pixel of our picture (anti-aliasing only: at 16 the drawing adds ≲ 0.005 of
    relative error at the silhouettes). The reference is the mean of two independent renders of
    ``spp_reference`` samples each, with its noise measured and cached
    (:func:`translucency.render.reference.converged_reference`; ``reference_cache`` as there).
    ``progress(done, total, step)`` is called as each step begins (transport, light, picture, reference).
    ``exposure``: of the PNGs (:class:`~translucency.render.tonemap.Exposure` or its text: ``fixed``,
    ``fixed+STOPS``, ``auto``, a factor); the FLIP comparison tone-maps the pair at the reference's auto
    exposure whatever the pictures' (``flip_exposure`` in the summary where they differ).

    Writes ``ours.exr/.png`` (and ``reference.exr/.png`` and ``NAME.png``, reference | ours | FLIP) and
    the summary ``NAME.json`` (``name``: ``render``; the paper's Figure 2 is ``figure2``) into
    ``out_dir``; returns the numbers.  The summary states the exposure (``exposure``, the factor on the
    linear radiance, and, unless it is ``auto``, ``exposure_rule``) and what was drawn (``incidence``,
    ``through``, ``angles``: :meth:`~translucency.transport.PreparedObject.describe`).
    """
    exposure = parse_exposure(exposure) if isinstance(exposure, str) else exposure
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    mesh = prepared.mesh
    camera = camera or Camera.looking_at(mesh)
    steps = 3 if volume is None else 4

    def step(k, what):
        if progress:
            progress(k, steps, what)

    # the calls run down the stage once: transport, picture, reference, comparison, files
    step(0, "transport (once per object)")
    t = time.perf_counter()
    prepared.build()  # the transport (and the lean's pairs, if drawn): once per object
    scene = prepared.shadow_scene  # for shadow rays
    t_prepare = time.perf_counter() - t
    step(1, "irradiance and relight")
    t = time.perf_counter()
    L, E = prepared.relight(light, camera.origin)
    t_relight = time.perf_counter() - t
    step(2, "picture")
    t = time.perf_counter()
    picture = VertexPicture(mesh, camera, spp=spp, eta=prepared.eta, light=light)  # the scene, built once
    t_prepare += time.perf_counter() - t  # building the picture's scene is part of the preparation
    t = time.perf_counter()
    ours = picture.draw(L)
    t_draw = time.perf_counter() - t
    mask = coverage(mesh, camera)
    drawn = prepared.describe()
    out = {
        "vertices": len(mesh.vertices),
        "transport_nonzeros": prepared.transport.nnz,
        "prepare_s": t_prepare,
        "relight_s": t_relight,
        "draw_s": t_draw,
        "light": repr(light),
        "eta": prepared.eta,
        "incidence": drawn["incidence"],
        "through": drawn["through"],
        "angles": prepared.leans_for(light),
    }
    model = prepared.model
    if volume is None:
        scale = _exposure(exposure, model, mesh, light, out, auto=lambda: auto_exposure(ours, mask))
        save_images(ours, out_dir / "ours", scale)
        write_json(out_dir / f"{name}.json", out)
        return out
    step(3, "volpath reference (2 renders, cached)")
    reference, ref_info = converged_reference(
        mesh, volume, light, camera, mask, spp=spp_reference, eta=prepared.eta, cache=reference_cache
    )
    cmp = _compared(out, reference, ours, mask, region_errors(mesh, scene, camera, E, reference, ours, mask))
    _timed(out, ref_info, spp_reference, t_prepare + t_relight + t_draw)
    scale = _exposure(exposure, model, mesh, light, out, auto=lambda: cmp["exposure"])
    if scale != cmp["exposure"] and cmp["flip_map"] is not None:  # FLIP measured at another exposure
        out["flip_exposure"] = cmp["exposure"]
    save_images(reference, out_dir / "reference", scale)
    save_images(ours, out_dir / "ours", scale)
    ldr = tonemap(reference, scale), tonemap(ours, scale)
    what = "fitted per-vertex model + through-body table" if out["through"] else "fitted per-vertex model"
    _plot(ldr, cmp["flip_map"], mask, out, out_dir / f"{name}.png", f"ours: {what}, sparse transport")
    write_json(out_dir / f"{name}.json", out)
    return out


def _compared(out: dict, reference, ours, mask, regions) -> dict:
    """The comparison of ours with the reference into ``out`` (its numbers, ``regions``); returns it with
    its ``flip_map`` (None without the flip extra) and ``exposure``."""
    cmp = compare(reference, ours, mask)
    flip_map = cmp.pop("flip_map")
    out.update(cmp)
    out["regions"] = regions
    return {**cmp, "flip_map": flip_map}


def _timed(out: dict, ref_info: dict, spp_reference: int, ours_s: float) -> None:
    """The reference's time, noise and samples into ``out``, and our speed-up over it."""
    out.update(
        {
            "reference_s": ref_info["seconds"],
            "reference_noise": ref_info["noise"],
            "reference_cached": ref_info["cached"],
            "reference_spp": spp_reference,
            "speedup_vs_reference": ref_info["seconds"] / ours_s,
        }
    )


def _exposure(exposure: Exposure, model, mesh, light, out: dict, auto) -> float:
    """The PNGs' exposure factor, stated in ``out`` (``exposure``, and ``exposure_rule`` unless auto).

    A fixed exposure needs the object's reflectance R — the median over incident points of the model's
    total reflectance (mean of the channels) times the median α — and the light's irradiance E at the
    relative lights' default distance (:data:`~translucency.render.lights.DEFAULT_DISTANCE` object sizes);
    where either is not a finite positive number (a black light, a broken model) the picture is exposed
    ``auto`` and the rule says why.
    """
    rule = None
    if exposure.rule == "scale":
        scale = float(exposure.scale)
        rule = f"given: the factor {scale:g}"
    elif exposure.rule == "fixed":
        distance = DEFAULT_DISTANCE * Placement.of(mesh).size
        with np.errstate(all="ignore"):
            R = float(np.median(model.total_reflectance().mean(axis=1)) * np.median(model.alpha.values))
            E = float(light.irradiance_scale(distance))
        try:
            scale = exposure.fixed(reflectance=R, irradiance=E) if R > 0 and E > 0 else math.nan
        except (ZeroDivisionError, OverflowError):  # R E so small or large that the factor is no number
            scale = math.nan
        if math.isfinite(scale) and scale > 0:
            rule = exposure.describe(reflectance=R, irradiance=E, distance=distance)
        else:
            scale = float(auto())
            rule = f"auto: no fixed exposure for a reflectance of {R:.4g} under {E:.4g} W/mm^2"
    else:
        scale = float(auto())
    out["exposure"] = scale
    if rule is not None:
        out["exposure_rule"] = rule
    return scale


def plot_comparison(ref_ldr, our_ldr, error_map, path, titles) -> None:
    """reference | ours | an error map (0..1, NaN where not compared) side by side into ``path``;
    ``titles``: the three panels' titles (also :func:`translucency.workflow.render_scene`'s figure)."""
    plt = pyplot()

    fig, ax = plt.subplots(1, 3, figsize=(13, 3.8))
    ax[0].imshow(ref_ldr)
    ax[1].imshow(our_ldr)
    im = ax[2].imshow(error_map, cmap="magma", vmin=0, vmax=1)
    for a, title in zip(ax, titles):
        a.set_title(title, fontsize=9)
    fig.colorbar(im, ax=ax[2], shrink=0.8)
    for a in ax:
        a.axis("off")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)


def _plot(ldr, flip_map, mask, cmp: dict, path, title: str) -> None:
    """reference | ours | FLIP error into ``path``; ``ldr``: the tone-mapped (reference, ours).  Without
    the flip extra (``flip_map`` None) the third panel is the tone-mapped pair's difference."""
    if flip_map is None:
        error = np.abs(ldr[1] - ldr[0]).mean(axis=-1)
        what = "|ours - ref.| tone-mapped (no FLIP)"
    else:
        error, what = flip_map, f"FLIP (object mean {cmp['flip_mean_object']:.3f})"
    plot_comparison(
        ldr[0],
        ldr[1],
        np.where(mask, error, np.nan),
        path,
        ("reference: Mitsuba volpath of the volume", title, f"{what}; rel. RMSE {cmp['rel_rmse']:.2f}"),
    )
