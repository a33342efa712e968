"""Where the object sits (:class:`Placement`) and a light placed relative to it (:class:`RelativeLight`):
azimuth and elevation around its centre, or along the camera's direction, at a distance in mm or object
sizes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._validate import TranslucencyError
from .light import (
    DEFAULT_CUTOFF_DEG,
    DEFAULT_DISTANCE,
    DEFAULT_IRRADIANCE,
    KEY_RAISE_DEG,
    KEY_TURN_DEG,
    KINDS,
    Light,
)


@dataclass(frozen=True)
class Placement:
    """Where the object sits and where it is seen from: what a light placed relative to it needs.

    ``bounds``: its bounding box, (2, 3) mm; ``view``: the unit direction from its centre towards the
    camera (None: no camera; ``camera`` and ``back`` then cannot be resolved).

    Examples
    --------
    >>> p = Placement(((-10.0, -10.0, 0.0), (10.0, 10.0, 20.0)), view=(0.0, -1.0, 0.0))
    >>> p.centre, round(p.size, 2)
    ((0.0, 0.0, 10.0), 34.64)
    """

    bounds: tuple
    view: tuple | None = None

    @classmethod
    def of(cls, mesh, view=None) -> Placement:
        """The placement of a (trimesh) mesh, seen from ``view`` (a direction from its centre)."""
        bounds = tuple(tuple(float(x) for x in row) for row in np.asarray(mesh.bounds, dtype=np.float64))
        if view is not None:
            v = np.asarray(view, dtype=np.float64)
            view = tuple(float(x) for x in v / np.linalg.norm(v))
        return cls(bounds, view)

    @property
    def centre(self) -> tuple:
        """The centre of the bounding box, mm (the camera looks at it)."""
        lo, hi = np.asarray(self.bounds, dtype=np.float64)
        return tuple(float(x) for x in 0.5 * (lo + hi))

    @property
    def size(self) -> float:
        """The object's size: its bounding box's diagonal, mm."""
        lo, hi = np.asarray(self.bounds, dtype=np.float64)
        return float(np.linalg.norm(hi - lo))

    def describe(self) -> str:
        """One line: the centre, the size and the extent along each axis, mm."""
        f = "{:.1f}" if self.size >= 10 else "{:.3g}"  # tenths of a mm, or 3 digits on a small object
        c = ", ".join(f.format(x) for x in self.centre)
        axes = ", ".join(f"{a} {f.format(lo)}…{f.format(hi)}" for a, lo, hi in zip("xyz", *self.bounds))
        return f"object: centre ({c}) mm, size {f.format(self.size)} mm (bounding-box diagonal); {axes} mm"


@dataclass(frozen=True)
class RelativeLight:
    """A point, spot or directional light placed relative to the object; :meth:`place` resolves it.

    The light lies in the direction (azimuth, elevation) from the object's centre: azimuth in degrees
    from +x towards +y, elevation in degrees above the xy plane (+z up); or along the camera's direction
    (``anchor="camera"``: from the camera's side) or opposite it (``"back"``: behind the object, seen
    from the camera), or beside and above it (``"key"``: the camera's direction turned
    :data:`~.light.KEY_TURN_DEG` about +z and raised :data:`~.light.KEY_RAISE_DEG`). A point or spot stands
    ``distance`` from the centre (mm, or object sizes with ``in_sizes``), a spot aimed at the centre; a
    directional light comes from that direction.
    """

    kind: str
    azimuth: float | None = None
    elevation: float | None = None
    anchor: str | None = None
    distance: float = DEFAULT_DISTANCE
    in_sizes: bool = True
    cutoff_deg: float = DEFAULT_CUTOFF_DEG
    power: float | None = None

    def direction(self, placement: Placement) -> np.ndarray:
        """The unit direction from the object's centre towards the light."""
        if self.anchor is not None:
            if placement.view is None:
                raise TranslucencyError(f"light: '{self.anchor}' needs the camera's direction (view=)")
            u = np.asarray(placement.view, dtype=np.float64)
            if self.anchor == "key":  # the view's azimuth turned, its elevation raised (at most 85°)
                az = np.arctan2(u[1], u[0]) + np.radians(KEY_TURN_DEG)
                el = min(np.arcsin(np.clip(u[2], -1.0, 1.0)) + np.radians(KEY_RAISE_DEG), np.radians(85.0))
                return np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
            return u if self.anchor == "camera" else -u
        az, el = np.radians(self.azimuth), np.radians(self.elevation)
        return np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])

    def distance_mm(self, placement: Placement) -> float:
        """A point's or spot's distance from the object's centre, mm (``distance`` in object sizes or mm)."""
        return float(self.distance * placement.size if self.in_sizes else self.distance)

    def position(self, placement: Placement) -> tuple[tuple, np.ndarray]:
        """A point's or spot's position (mm) ``distance`` from the object's centre towards the light, and
        the centre."""
        u = self.direction(placement)
        centre = np.asarray(placement.centre, dtype=np.float64)
        return tuple(float(x) for x in centre + self.distance_mm(placement) * u), centre

    def power_or(self, default: float) -> float:
        """Its power, or ``default`` where its text gave none."""
        return float(default if self.power is None else self.power)

    def intensity(self, placement: Placement) -> float:
        """A point's or spot's I (W/sr): its power, or where its text gave none the I that brings
        :data:`~.light.DEFAULT_IRRADIANCE` to the object's centre from its distance d: E d²."""
        return self.power_or(DEFAULT_IRRADIANCE * self.distance_mm(placement) ** 2)

    def place(self, placement: Placement) -> Light:
        """The light in the object's frame: its kind's :meth:`~.light.Light.placed`."""
        return KINDS[self.kind].placed(self, placement)
