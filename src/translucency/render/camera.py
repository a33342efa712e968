"""The camera of a rendering: a perspective pinhole in mm and degrees, and its Mitsuba sensor."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError
from ..mitsuba import pinhole_sensor_dict


def view_direction(view, name: str = "view") -> np.ndarray:
    """The unit direction from the object's centre towards the camera, from three numbers (or their
    ``x,y,z`` text); one line naming ``name`` when they are not three finite numbers, not all zero.

    Examples
    --------
    >>> view_direction("0,0,2").tolist()
    [0.0, 0.0, 1.0]
    """
    try:
        parts = view.split(",") if isinstance(view, str) else view
        direction = np.asarray([float(v) for v in parts], dtype=np.float64)
    except (TypeError, ValueError):
        direction = np.zeros(0)
    if direction.shape != (3,) or not np.isfinite(direction).all() or not np.abs(direction).max() > 0:
        raise TranslucencyError(f"{name}: expected three finite numbers x,y,z not all zero, got {view!r}")
    direction = direction / np.abs(direction).max()  # 1e308 or 1e-320: no overflow, no 0
    return direction / np.linalg.norm(direction)


@dataclass(frozen=True)
class Camera:
    """A perspective camera (mm, degrees); ``looking_at`` frames an object.

    ``looking_at`` aims at the centre of the mesh's bounding box from ``direction``, 1.9 bounding-box
    diagonals away, with a 35° field of view; the image's up is +z (+y looking straight up or down).

    Examples
    --------
    >>> import trimesh
    >>> box = trimesh.creation.box(extents=(10.0, 10.0, 10.0)).apply_translation((0.0, 0.0, 5.0))
    >>> cam = Camera.looking_at(box, direction=(1.0, 0.0, 0.0), width=64, height=48)
    >>> [round(float(x), 3) for x in cam.origin], [float(x) for x in cam.target]  # 1.9 × 17.32 mm along x
    ([32.909, 0.0, 5.0], [0.0, 0.0, 5.0])
    >>> cam.up, cam.fov, (cam.width, cam.height)
    ((0.0, 0.0, 1.0), 35.0, (64, 48))
    >>> Camera.looking_at(box, direction=(0.0, 0.0, 1.0)).up  # from straight above: +y is up
    (0.0, 1.0, 0.0)
    >>> film = cam.sensor_dict(spp=4)["film"]
    >>> film["width"], film["height"]
    (64, 48)
    """

    origin: tuple
    target: tuple
    up: tuple = (0.0, 0.0, 1.0)
    fov: float = 35.0
    width: int = 320
    height: int = 240

    @classmethod
    def looking_at(cls, mesh, direction=(1.0, -1.6, 0.7), width: int = 320, height: int = 240) -> Camera:
        centre = mesh.bounds.mean(axis=0)
        d = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
        dist = 1.9 * float(np.linalg.norm(mesh.extents))
        # the image's up is +z, or +y when looking straight up or down
        up = (0.0, 1.0, 0.0) if abs(d[2]) > 0.999 else (0.0, 0.0, 1.0)
        return cls(tuple(centre + dist * d), tuple(centre), up, 35.0, width, height)

    def sensor_dict(self, spp: int) -> dict:
        """The Mitsuba ``perspective`` sensor of this camera (box filter, RGB film), ``spp`` samples a
        pixel; the clipping planes are Mitsuba's defaults."""
        return pinhole_sensor_dict(self, spp)
