"""The isotropic point light: intensity I (W/sr) at a position (mm)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..._validate import TranslucencyError, plain
from ...mitsuba import mitsuba
from .light import DEFAULT_INTENSITY, _DeltaLight

if TYPE_CHECKING:  # the placement's types, for the signatures only
    from .placement import Placement, RelativeLight


def _from_position(scene, position, intensity, x, n) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:meth:`_DeltaLight.arrival` of an isotropic intensity I (W/sr) at ``position`` (mm); a one-line
    error for a position inside the object."""
    mi = mitsuba()
    p = np.asarray(position, dtype=np.float64)
    # inside a closed, outward-oriented surface a ray first meets a face from its back
    probe = scene.ray_intersect(mi.Ray3f(mi.Point3f(*map(float, p)), mi.Vector3f(0.5773, 0.5774, 0.5773)))
    if (
        bool(probe.is_valid()[0])
        and float(
            np.asarray(probe.n.x)[0] * 0.5773
            + np.asarray(probe.n.y)[0] * 0.5774
            + np.asarray(probe.n.z)[0] * 0.5773
        )
        > 0
    ):
        raise TranslucencyError(f"light: the point light at {plain(p)} mm is inside the object")
    to = p - x
    dist = np.linalg.norm(to, axis=1)
    w = to / dist[:, None]
    E = intensity * np.maximum((w * n).sum(1), 0.0) / dist**2
    return w, E, dist


@dataclass(frozen=True)
class PointLight(_DeltaLight):
    """Isotropic point light: intensity I (W/sr) at ``position`` (mm).

    Examples
    --------
    >>> import trimesh
    >>> from translucency.mitsuba import mesh_scene
    >>> scene = mesh_scene(trimesh.creation.box(extents=(10.0, 10.0, 10.0)))
    >>> x = np.array([[0.0, 0.0, 5.0], [5.0, 0.0, 0.0], [-5.0, 0.0, 0.0]])  # on the top, +x and −x faces
    >>> n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    >>> lamp = PointLight((20.0, 0.0, 25.0), intensity=800.0)
    >>> lamp.irradiance_at(scene, x, n, extent=10.0).round(4)  # I cos θ / d²: 800 cos 45° / 800, ...
    array([0.7071, 0.4842, 0.    ])
    >>> round(800.0 * (15.0 / 850.0**0.5) / 850.0, 4)  # ... the +x face: 15 mm across, 25 up
    0.4842
    >>> lamp.irradiance_scale(20.0)  # I / d² on a surface facing it 20 mm away
    2.0
    >>> PointLight((0.0, 0.0, 0.0)).irradiance_at(scene, x, n, extent=10.0)
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: light: the point light at (0, 0, 0) mm is inside the object
    """

    kind = prefix = "point"
    forms = "point:x,y,z[,I]"
    counts, power_index = (3, 4), 3
    relative_tail = ("distance", "intensity")
    relative_form = "point@AZ,EL[,DIST[,I]]"
    distant = False

    position: tuple
    intensity: float = DEFAULT_INTENSITY

    @classmethod
    def of_numbers(cls, text: str, v: list) -> PointLight:
        return cls(tuple(v[:3]), *(v[3:] or []))

    @classmethod
    def placed(cls, relative: RelativeLight, placement: Placement) -> PointLight:
        position, _ = relative.position(placement)
        return cls(position, relative.intensity(placement))

    def emitter_dict(self) -> dict:
        return {
            "type": "point",
            "position": [float(v) for v in self.position],
            "intensity": float(self.intensity),
        }

    def irradiance_scale(self, distance: float) -> float:
        """Irradiance (W/mm²) on a surface facing the light at ``distance`` mm: I / d²."""
        return float(self.intensity) / float(distance) ** 2

    def arrival(self, scene, x, n):
        return _from_position(scene, self.position, self.intensity, x, n)
