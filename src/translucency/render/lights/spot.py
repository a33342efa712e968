"""The spot light: a point light aimed at a target, its intensity I (W/sr) inside a cone with Mitsuba's
falloff (:data:`translucency.mitsuba.SPOT_BEAM_FRACTION`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..._validate import TranslucencyError
from ...mitsuba import SPOT_BEAM_FRACTION, spot_dict
from .light import DEFAULT_INTENSITY, MIN_CUTOFF_DEG, _DeltaLight
from .point import _from_position

if TYPE_CHECKING:  # the placement's types, for the signatures only
    from .placement import Placement, RelativeLight


@dataclass(frozen=True)
class SpotLight(_DeltaLight):
    """A point light at ``position`` aimed at ``target`` (mm), intensity I (W/sr) inside a cone.

    Mitsuba's falloff: full intensity within ``SPOT_BEAM_FRACTION × cutoff``, falling linearly in
    angle to 0 at ``cutoff``.

    Examples
    --------
    >>> spot = SpotLight((0.0, 0.0, 25.0), (0.0, 0.0, 0.0), cutoff_deg=20.0, intensity=800.0)
    >>> spot.beam_width_deg  # full intensity within 0.75 × the cutoff
    15.0
    >>> off_axis = lambda deg: np.array([[np.sin(np.radians(deg)), 0.0, -np.cos(np.radians(deg))]])
    >>> [round(float(spot.falloff(off_axis(a))[0]), 3) for a in (0.0, 15.0, 17.5, 20.0, 30.0)]
    [1.0, 1.0, 0.5, 0.0, 0.0]
    >>> import trimesh
    >>> from translucency.mitsuba import mesh_scene
    >>> scene = mesh_scene(trimesh.creation.box(extents=(10.0, 10.0, 10.0)))
    >>> top, up = np.array([[0.0, 0.0, 5.0]]), np.array([[0.0, 0.0, 1.0]])  # on its axis, 20 mm below it
    >>> spot.irradiance_at(scene, top, up, extent=10.0)  # I / d² = 800 / 20²
    array([2.])
    """

    kind = prefix = "spot"
    forms = "spot:x,y,z,tx,ty,tz,cutoff[,I]"
    counts, power_index = (7, 8), 7
    relative_tail = ("distance", "cutoff", "intensity")
    relative_form = "spot@AZ,EL[,DIST[,CUTOFF[,I]]]"
    distant = False

    position: tuple
    target: tuple
    cutoff_deg: float = 20.0
    intensity: float = DEFAULT_INTENSITY

    @classmethod
    def of_numbers(cls, text: str, v: list) -> SpotLight:
        if np.allclose(v[:3], v[3:6]):
            raise TranslucencyError(f"light: the spot in {text!r} is aimed at its own position")
        if not MIN_CUTOFF_DEG <= v[6] < 90:
            raise TranslucencyError(
                f"light: the spot's cutoff angle in {text!r} must lie in [{MIN_CUTOFF_DEG:g}, 90) degrees"
            )
        return cls(tuple(v[:3]), tuple(v[3:6]), *v[6:])

    @classmethod
    def placed(cls, relative: RelativeLight, placement: Placement) -> SpotLight:
        position, centre = relative.position(placement)
        intensity = relative.intensity(placement)
        return cls(position, tuple(float(x) for x in centre), float(relative.cutoff_deg), intensity)

    @property
    def beam_width_deg(self) -> float:
        """Angle up to which the intensity is full."""
        return SPOT_BEAM_FRACTION * self.cutoff_deg

    def falloff(self, w_from_light: np.ndarray) -> np.ndarray:
        """The fraction of I sent along unit directions (N, 3) leaving the light."""
        axis = np.asarray(self.target, float) - np.asarray(self.position, float)
        axis /= np.linalg.norm(axis)
        theta = np.degrees(np.arccos(np.clip(w_from_light @ axis, -1.0, 1.0)))
        return np.clip((self.cutoff_deg - theta) / (self.cutoff_deg - self.beam_width_deg), 0.0, 1.0)

    def emitter_dict(self) -> dict:
        return spot_dict(self.position, self.target, self.cutoff_deg, self.intensity)

    def irradiance_scale(self, distance: float) -> float:
        """Irradiance (W/mm²) on a surface facing the light inside its cone at ``distance`` mm: I / d²."""
        return float(self.intensity) / float(distance) ** 2

    def arrival(self, scene, x, n):
        w, E, dist = _from_position(scene, self.position, self.intensity, x, n)
        return w, E * self.falloff(-w), dist
