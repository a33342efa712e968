"""The directional light: irradiance E (W/mm²) on a surface facing it, from infinitely far."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..._validate import TranslucencyError
from ...transport import sh
from .light import DEFAULT_IRRADIANCE, _DeltaLight

if TYPE_CHECKING:  # the placement's types, for the signatures only
    from .placement import Placement, RelativeLight


@dataclass(frozen=True)
class DirectionalLight(_DeltaLight):
    """Distant light: irradiance E (W/mm²) on a surface facing it, travelling along ``direction``.

    Examples
    --------
    >>> import trimesh
    >>> from translucency.mitsuba import mesh_scene
    >>> scene = mesh_scene(trimesh.creation.box(extents=(10.0, 10.0, 10.0)))
    >>> x = np.array([[0.0, 0.0, 5.0], [5.0, 0.0, 0.0], [-5.0, 0.0, 0.0]])  # on the top, +x and −x faces
    >>> n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    >>> theta = np.radians(60.0)  # arriving from +x, 60° from the vertical
    >>> sun = DirectionalLight((-np.sin(theta), 0.0, -np.cos(theta)), irradiance=2.0)
    >>> sun.irradiance_at(scene, x, n, extent=10.0).round(4)  # E cos θ: 2 cos 60°, 2 cos 30°, facing away
    array([1.    , 1.7321, 0.    ])
    >>> sun.irradiance_scale(1e3), sun.distant, sun.delta  # E at any distance, along one direction
    (2.0, True, True)
    """

    kind = prefix = "directional"
    forms = "directional:dx,dy,dz[,E] (the direction the light travels)"
    counts, power_index = (3, 4), 3
    relative_tail = ("irradiance",)
    relative_form = "directional@AZ,EL[,E]"
    distant = True

    direction: tuple
    irradiance: float = DEFAULT_IRRADIANCE

    def __post_init__(self):
        # a unit direction, however it was given (the irradiance E cos θ and Mitsuba's emitter agree)
        d = np.asarray(self.direction, dtype=np.float64)
        if d.shape != (3,) or not (np.isfinite(d).all() and np.linalg.norm(d) > 0):
            raise TranslucencyError(
                f"light: a directional light needs a finite non-zero direction, got {self.direction}"
            )
        object.__setattr__(self, "direction", tuple(float(x) for x in d / np.linalg.norm(d)))

    @classmethod
    def of_numbers(cls, text: str, v: list) -> DirectionalLight:
        d = np.asarray(v[:3])
        if not np.linalg.norm(d) > 0:
            raise TranslucencyError("light: a directional light needs a non-zero direction")
        return cls(tuple(float(x) for x in d / np.linalg.norm(d)), *(v[3:] or []))

    @classmethod
    def placed(cls, relative: RelativeLight, placement: Placement) -> DirectionalLight:
        u = relative.direction(placement)
        return cls(tuple(float(x) for x in -u), relative.power_or(DEFAULT_IRRADIANCE))

    def emitter_dict(self) -> dict:
        return {
            "type": "directional",
            "direction": [float(v) for v in self.direction],
            "irradiance": float(self.irradiance),
        }

    def irradiance_scale(self, distance: float) -> float:
        """Irradiance (W/mm²) on a surface facing the light: E, at any distance."""
        return float(self.irradiance)

    def arrival(self, scene, x, n):
        w = -np.asarray(self.direction, dtype=np.float64)
        E = self.irradiance * np.maximum(n @ w, 0.0)
        return np.broadcast_to(w, x.shape), E, np.full(len(x), 1e7)

    def sh_coefficients(self, bands: int) -> np.ndarray:
        r""":math:`L_k = E\, Y_k(\omega_l)`, :math:`\omega_l` the direction it arrives from."""
        d = -np.asarray(self.direction, dtype=np.float64)  # the light arrives from −direction
        return sh.project_directional(d / np.linalg.norm(d), self.irradiance, bands)
