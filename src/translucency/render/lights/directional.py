"""The directional light: irradiance E (W/mm²) on a surface facing it, from infinitely far."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..._validate import TranslucencyError
from .. import sh
from .light import DEFAULT_IRRADIANCE, _DeltaLight

if TYPE_CHECKING:  # the placement's types, for the signatures only
    from .placement import Placement, RelativeLight


@dataclass(frozen=True)
class DirectionalLight(_DeltaLight):
    """Distant light: irradiance E (W/mm²) on a surface facing it, travelling along ``direction``."""

    kind = prefix = "directional"
    forms = "directional:dx,dy,dz[,E] (the direction the light travels)"
    counts, power_index = (3, 4), 3
    relative_tail = ("irradiance",)
    relative_form = "directional@AZ,EL[,E]"
    distant = True

    direction: tuple
    irradiance: float = DEFAULT_IRRADIANCE

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
