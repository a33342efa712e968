"""The camera of a rendering: a perspective pinhole in mm and degrees, and its Mitsuba sensor."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mitsuba import pinhole_sensor_dict


@dataclass(frozen=True)
class Camera:
    """A perspective camera (mm, degrees); ``looking_at`` frames an object."""

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
        return cls(tuple(centre + dist * d), tuple(centre), (0.0, 0.0, 1.0), 35.0, width, height)

    def sensor_dict(self, spp: int) -> dict:
        """The Mitsuba ``perspective`` sensor of this camera (box filter, RGB film), ``spp`` samples a
        pixel; the clipping planes are Mitsuba's defaults."""
        return pinhole_sensor_dict(self, spp)
