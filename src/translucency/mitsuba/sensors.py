"""Mitsuba's cameras from ours: ``to_world`` looking at a target (:func:`look_at`), the ``perspective``
sensor of a pinhole camera, of a calibrated camera's 4 × 4 pose, or at a position looking at a target, each
with an RGB ``hdrfilm`` and a box filter (a pixel's value is the mean radiance over its footprint).
Units: mm, fields of view in degrees.
"""

from __future__ import annotations

import numpy as np

from ._engine import mitsuba

__all__ = ["look_at", "perspective_camera_dict", "perspective_to_world_dict", "pinhole_sensor_dict"]


def look_at(origin, target, up=None):
    """Mitsuba's ``to_world`` looking from ``origin`` at ``target`` (mm); ``up`` chosen off the axis if not
    given.

    Examples
    --------
    >>> mi = mitsuba()
    >>> to_world = look_at((0, 0, 10), (0, 0, 0))   # looking straight down from 10 mm
    >>> list(to_world @ mi.ScalarPoint3f(0, 0, 0)), list(to_world @ mi.ScalarVector3f(0, 0, 1))
    ([0.0, 0.0, 10.0], [0.0, 0.0, -1.0])
    """
    if up is None:
        axis = np.asarray(target, float) - np.asarray(origin, float)
        up = [0.0, 0.0, 1.0] if abs(axis[2]) < 0.99 * np.linalg.norm(axis) else [0.0, 1.0, 0.0]
    return (
        mitsuba()
        .ScalarTransform4f()
        .look_at(
            origin=[float(v) for v in origin], target=[float(v) for v in target], up=[float(v) for v in up]
        )
    )


def perspective_camera_dict(
    origin, target, fov_deg: float, width: int, height: int, spp: int = 16, up=None, *, far_clip=1e5
) -> dict:
    """Mitsuba ``perspective`` sensor at ``origin`` looking at ``target`` (mm), horizontal field of view
    ``fov_deg``, an RGB ``hdrfilm`` of ``width`` × ``height`` pixels with a box filter (a pixel's value is
    the mean radiance over its footprint).

    ``far_clip`` (mm) with the near clip at 0.01 mm; None leaves both and the field of view's axis to
    Mitsuba's defaults (the renderer's :class:`translucency.render.Camera`).

    Examples
    --------
    >>> from translucency.mitsuba import load_plugin
    >>> camera = perspective_camera_dict((0, 0, 100), (0, 0, 0), fov_deg=30, width=64, height=48, spp=4)
    >>> camera["fov_axis"], camera["far_clip"], list(load_plugin(camera).film().size())
    ('x', 100000.0, [64, 48])
    """
    clip = {} if far_clip is None else {"fov_axis": "x", "near_clip": 1e-2, "far_clip": float(far_clip)}
    return _perspective(look_at(origin, target, up), fov_deg, width, height, spp, clip)


def _perspective(to_world, fov_deg: float, width: int, height: int, spp: int, clip: dict) -> dict:
    """A ``perspective`` sensor: ``to_world``, field of view, clipping ``clip``, an RGB ``hdrfilm`` of
    ``width`` × ``height`` with a box filter, ``spp`` independent samples a pixel."""
    return {
        "type": "perspective",
        "fov": float(fov_deg),
        **clip,
        "to_world": to_world,
        "film": {
            "type": "hdrfilm",
            "width": int(width),
            "height": int(height),
            "rfilter": {"type": "box"},
            "pixel_format": "rgb",
        },
        "sampler": {"type": "independent", "sample_count": int(spp)},
    }


def perspective_to_world_dict(
    to_world: np.ndarray, fov_deg: float, width: int, height: int, spp: int
) -> dict:
    """Mitsuba ``perspective`` sensor with a 4 × 4 ``to_world`` (Mitsuba's camera frame: left, up,
    forward), horizontal field of view ``fov_deg``, an RGB ``hdrfilm`` with a box filter, ``spp`` samples
    (a calibrated camera's, :meth:`translucency.rig.object.cameras.Camera.sensor_dict`).

    Examples
    --------
    >>> from translucency.mitsuba import load_plugin
    >>> to_world = np.eye(4)
    >>> to_world[:3, 3] = [1.0, 2.0, 3.0]   # a camera at (1, 2, 3) mm
    >>> sensor = perspective_to_world_dict(to_world, 40.0, 32, 24, spp=1)
    >>> list(sensor["to_world"].translation()), list(load_plugin(sensor).film().size())
    ([1.0, 2.0, 3.0], [32, 24])
    """
    to_world = mitsuba().ScalarTransform4f(np.asarray(to_world, dtype=np.float64).tolist())
    clip = {"fov_axis": "x", "near_clip": 1e-2, "far_clip": 1e5}
    return _perspective(to_world, fov_deg, width, height, spp, clip)


def pinhole_sensor_dict(camera, spp: int) -> dict:
    """The ``perspective`` sensor of a pinhole ``camera`` (its ``origin``, ``target``, ``up`` in mm, ``fov``
    in degrees, ``width`` × ``height`` pixels; :class:`translucency.render.Camera`), ``spp`` samples a
    pixel, with Mitsuba's default clipping planes.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> camera = SimpleNamespace(origin=(0, 0, 100), target=(0, 0, 0), up=(0, 1, 0), fov=30.0, width=16,
    ...                          height=16)
    >>> sensor = pinhole_sensor_dict(camera, spp=2)
    >>> "near_clip" in sensor, sensor["sampler"]["sample_count"]   # Mitsuba's clipping planes
    (False, 2)
    """
    return perspective_camera_dict(
        camera.origin,
        camera.target,
        camera.fov,
        camera.width,
        camera.height,
        spp,
        up=camera.up,
        far_clip=None,
    )
