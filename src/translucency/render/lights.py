"""Lights of a rendering: point, spot, directional and environment (constant sky or map).

Each light is a small frozen dataclass in mm and W: it knows its own Mitsuba
emitter (:meth:`emitter_dict`), used alike for the irradiance at the vertices,
for our picture and for the ``volpath`` reference, so the conventions live in
one place.  The spot's falloff is Mitsuba's (:data:`translucency.mitsuba.SPOT_BEAM_FRACTION`).

Units: point and spot intensity I in W/sr, directional irradiance E in W/mm²,
environment radiance L in W/(mm² sr).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError
from ..mitsuba import SPOT_BEAM_FRACTION, load_plugin, mitsuba, spot_dict

#: the largest power (I in W/sr, E in W/mm², L and a map's scale in W/(mm² sr)) a light may have: far
#: beyond any lamp or the sun, well inside float32, so that irradiance, transport and pictures stay finite
MAX_POWER = 1e20
#: the largest coordinate of a light's position or target, mm (a kilometre is 1e6 mm)
MAX_COORDINATE = 1e12
#: the narrowest spot cone, degrees (Mitsuba's falloff divides by the cone's width)
MIN_CUTOFF_DEG = 0.01


@dataclass(frozen=True)
class PointLight:
    """Isotropic point light: intensity I (W/sr) at ``position`` (mm)."""

    position: tuple
    intensity: float = 1.0e4

    def emitter_dict(self) -> dict:
        """The Mitsuba emitter of this light."""
        return {
            "type": "point",
            "position": [float(v) for v in self.position],
            "intensity": float(self.intensity),
        }


@dataclass(frozen=True)
class DirectionalLight:
    """Distant light: irradiance E (W/mm²) on a surface facing it, travelling along ``direction``."""

    direction: tuple
    irradiance: float = 1.0

    def emitter_dict(self) -> dict:
        """The Mitsuba emitter of this light."""
        return {
            "type": "directional",
            "direction": [float(v) for v in self.direction],
            "irradiance": float(self.irradiance),
        }


@dataclass(frozen=True)
class SpotLight:
    """A point light at ``position`` aimed at ``target`` (mm), intensity I (W/sr) inside a cone.

    Mitsuba's falloff: full intensity within ``SPOT_BEAM_FRACTION × cutoff``, falling linearly in
    angle to 0 at ``cutoff``.
    """

    position: tuple
    target: tuple
    cutoff_deg: float = 20.0
    intensity: float = 1.0e4

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
        """The Mitsuba emitter of this light."""
        return spot_dict(self.position, self.target, self.cutoff_deg, self.intensity)


@dataclass(frozen=True)
class EnvironmentLight:
    """Light from every direction: a constant radiance L (W/(mm² sr)), or an environment map.

    With ``filename`` a latitude–longitude image (EXR, HDR, PNG; linear RGB) read by
    Mitsuba's ``envmap`` emitter, scaled by ``radiance``; the map's up axis (+Y)
    is turned to the scene's +Z, the same for the irradiance, our picture and
    the reference.
    """

    radiance: float = 0.1
    samples: int = 64  # visibility rays per vertex (cosine-weighted, or by the map's importance)
    filename: str | None = None

    def emitter_dict(self) -> dict:
        """The Mitsuba emitter of this light."""
        if self.filename is None:
            return {"type": "constant", "radiance": float(self.radiance)}
        return {
            "type": "envmap",
            "filename": str(self.filename),
            "scale": float(self.radiance),
            "to_world": mitsuba().ScalarTransform4f().rotate([1.0, 0.0, 0.0], 90.0),
        }


def parse_light(text: str):
    """``point:x,y,z[,I]``, ``directional:dx,dy,dz[,E]``, ``spot:x,y,z,tx,ty,tz,cutoff_deg[,I]``,
    ``env:L`` (constant) or ``env:MAP.exr[,scale]`` (environment map).

    Examples
    --------
    >>> parse_light("point:0,0,100,5e3")
    PointLight(position=(0.0, 0.0, 100.0), intensity=5000.0)
    """
    kind, _, rest = text.partition(":")
    if kind == "env" and rest:
        try:
            float(rest.split(",")[0])
        except ValueError:  # not a number: the name of an environment map
            return _environment_map(rest)
    try:
        v = [float(x) for x in rest.split(",")]
    except ValueError:
        raise TranslucencyError(f"light: cannot read numbers in {text!r}") from None
    if not np.isfinite(v).all():
        raise TranslucencyError(f"light: every number must be finite, got {text!r}")
    power = {"point": 3, "directional": 3, "spot": 7, "env": 0}.get(kind)
    if power is not None and len(v) > power and v[power] < 0:
        raise TranslucencyError(f"light: the intensity of {text!r} must be >= 0")
    if power is not None and len(v) > power and v[power] > MAX_POWER:
        raise TranslucencyError(f"light: the intensity of {text!r} must be at most {MAX_POWER:g}")
    if max((abs(x) for x in (v[:power] if power is not None else v)), default=0.0) > MAX_COORDINATE:
        raise TranslucencyError(
            f"light: positions and directions of {text!r} must lie within ±{MAX_COORDINATE:g}"
        )
    if kind == "spot" and len(v) >= 6 and np.allclose(v[:3], v[3:6]):
        raise TranslucencyError(f"light: the spot in {text!r} is aimed at its own position")
    if kind == "spot" and len(v) in (7, 8) and not MIN_CUTOFF_DEG <= v[6] < 90:
        raise TranslucencyError(
            f"light: the spot's cutoff angle in {text!r} must lie in [{MIN_CUTOFF_DEG:g}, 90) degrees"
        )
    if kind == "point" and len(v) in (3, 4):
        return PointLight(tuple(v[:3]), *(v[3:] or []))
    if kind == "directional" and len(v) in (3, 4):
        d = np.asarray(v[:3])
        if not np.linalg.norm(d) > 0:
            raise TranslucencyError("light: a directional light needs a non-zero direction")
        return DirectionalLight(
            tuple(float(x) for x in d / np.linalg.norm(d)), *(v[3:] or [])
        )  # plain floats
    if kind == "spot" and len(v) in (7, 8):
        return SpotLight(tuple(v[:3]), tuple(v[3:6]), *v[6:])
    if kind == "env" and len(v) == 1 and v[0] >= 0:
        return EnvironmentLight(v[0])
    raise TranslucencyError(
        "light: expected point:x,y,z[,I], directional:dx,dy,dz[,E], "
        f"spot:x,y,z,tx,ty,tz,cutoff_deg[,I], env:L or env:MAP.exr[,scale], got {text!r}"
    )


def _environment_map(rest: str) -> EnvironmentLight:
    """``MAP[,scale]`` of ``env:``: the file must exist and Mitsuba must read it."""
    name, _, scale = rest.partition(",")
    path = Path(name.strip())
    if not path.is_file():
        raise TranslucencyError(f"light: environment map {path} does not exist")
    try:
        s = float(scale) if scale.strip() else 1.0
    except ValueError:
        raise TranslucencyError(f"light: cannot read the scale {scale!r} of env:{rest}") from None
    if not (np.isfinite(s) and 0 <= s <= MAX_POWER):
        raise TranslucencyError(f"light: the scale of env:{rest} must lie in [0, {MAX_POWER:g}]")
    light = EnvironmentLight(s, filename=str(path.resolve()))
    try:
        pixels = np.asarray(mitsuba().Bitmap(str(path.resolve())), dtype=np.float64)
        load_plugin(light.emitter_dict())
    except Exception as exc:  # noqa: BLE001 — Mitsuba's message is long; one line names the file
        text = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise TranslucencyError(f"light: {path} is not a readable environment map ({text[:120]})") from None
    _check_map_pixels(path, pixels, s)
    return light


def _check_map_pixels(path: Path, pixels: np.ndarray, scale: float) -> None:
    """An environment map's pixels: a latitude–longitude image of finite, non-negative radiance."""
    if pixels.ndim not in (2, 3) or min(pixels.shape[:2]) < 1 or (pixels.ndim == 3 and pixels.shape[2] > 4):
        raise TranslucencyError(
            f"light: {path} is not a latitude-longitude image (pixel array of shape {pixels.shape})"
        )
    bad = ~np.isfinite(pixels)
    if bad.any():
        row, col = (int(x) for x in np.argwhere(bad)[0][:2])
        raise TranslucencyError(
            f"light: {path} holds {int(bad.sum())} non-finite values (NaN or infinity), the first at pixel "
            f"row {row}, column {col}"
        )
    if (pixels < 0).any():
        row, col = (int(x) for x in np.argwhere(pixels < 0)[0][:2])
        raise TranslucencyError(
            f"light: {path} holds negative radiance ({pixels.min():.3g} at pixel row {row}, column {col})"
        )
    if not pixels.max(initial=0.0) > 1e-30:  # Mitsuba's importance sampling of a black map divides by 0
        raise TranslucencyError(f"light: {path} is black (no pixel above 1e-30): it lights nothing")
    if pixels.max(initial=0.0) * scale > MAX_POWER:
        raise TranslucencyError(
            f"light: {path} times its scale reaches a radiance of {pixels.max() * scale:.3g}, more than "
            f"{MAX_POWER:g}"
        )
