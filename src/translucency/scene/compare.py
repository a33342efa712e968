r"""A scene picture against its reference, over the fitted objects and over the light they send to the rest.

Two sets of pixels: the **objects** (the pixel's centre ray first meets a fitted object) and the pixels
the objects **light** — off the objects, where our picture with the objects glowing exceeds the same
picture with them dark by at least :data:`LIT_SHARE` of its value (the floor under a back-lit object,
a wall beside it).  Over each: relative RMSE :math:`\lVert\hat I - I\rVert / \lVert I \rVert`, the mean
brightness ratio and (objects) the mean FLIP of the tone-mapped pair; the rest of the picture too.
"""

from __future__ import annotations

import numpy as np

from ..mitsuba import drjit, mitsuba
from ..render import compare, rel_rmse

#: the least share of a pixel's value the fitted objects must bring for the pixel to count as lit by them
LIT_SHARE = 0.1


def object_pixels(fitted_scene, sensor: int = 0) -> np.ndarray:
    """(H, W) bool: pixels whose centre ray first meets a fitted object."""
    mi, dr = mitsuba(), drjit()
    camera = fitted_scene.scene.sensors()[sensor]
    W, H = (int(v) for v in camera.film().crop_size())
    idx = dr.arange(mi.UInt32, W * H)
    pos = mi.Point2f((mi.Float(idx % W) + 0.5) / W, (mi.Float(idx // W) + 0.5) / H)
    ray, _ = camera.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    si = fitted_scene.scene.ray_intersect(ray)
    _, on = fitted_scene.glow.hit(si, dr.full(mi.Bool, True, W * H))
    return np.asarray(on, dtype=bool).reshape(H, W)


def lit_pixels(
    ours: np.ndarray, dark: np.ndarray, objects: np.ndarray, share: float = LIT_SHARE
) -> np.ndarray:
    """(H, W) bool: off the objects, where the objects' light is at least ``share`` of our picture."""
    a, b = ours.sum(axis=2), dark.sum(axis=2)
    return ~objects & (a > 0) & (a - b >= share * a)


def scene_errors(reference: np.ndarray, ours: np.ndarray, objects: np.ndarray, lit: np.ndarray) -> dict:
    """Errors of ``ours`` against ``reference`` (module docstring): ``object`` (rel_rmse, flip, brightness,
    pixels), ``lit`` and ``rest`` (rel_rmse, brightness, pixels); and ``flip_map``, the FLIP per pixel."""

    def part(mask):
        if not mask.any():
            return {"pixels": 0}
        return {
            "rel_rmse": rel_rmse(ours, reference, mask),
            "brightness": float(ours[mask].mean() / max(reference[mask].mean(), 1e-30)),
            "pixels": int(mask.sum()),
        }

    cmp = (
        compare(reference, ours, objects)
        if objects.any()
        else {"flip_mean_object": float("nan"), "flip_map": None}
    )
    out = {
        "object": {**part(objects), "flip": cmp.get("flip_mean_object", float("nan"))},  # nan: no flip extra
        "lit": part(lit),
        "rest": part(~objects),
        "flip_map": cmp["flip_map"],
    }
    return out
