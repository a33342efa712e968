"""Lights of a rendering: point, spot, directional and environment (constant sky or map).

Each light is a small frozen dataclass in mm and W: it knows its own Mitsuba
emitter (:meth:`emitter_dict`), used alike for the irradiance at the vertices,
for our picture and for the ``volpath`` reference, so the conventions live in
one place, and the irradiance it brings at a stated distance (:meth:`irradiance_scale`, the
scale of a fixed exposure).  The spot's falloff is Mitsuba's
(:data:`translucency.mitsuba.SPOT_BEAM_FRACTION`).

:func:`parse_light` reads a light's text.  Positions and directions are in the object's frame (mm,
+z up); a light may also be placed relative to the object (``point@AZ,EL,DIST``: azimuth and
elevation around the object's centre, a distance from it), resolved by :class:`RelativeLight` against
a :class:`Placement` (the object's bounds and the direction towards the camera).

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
#: the distance from the object's centre of a light placed relative to it when none is given, in object
#: sizes (the size: its bounding box's diagonal); the camera sits at 1.9
DEFAULT_DISTANCE = 1.5
#: the power of a light when none is given, in every form: I of a point or spot (W/sr), E of a
#: directional light (W/mm²)
DEFAULT_INTENSITY = 1.0e4
DEFAULT_IRRADIANCE = 1.0
#: the cone of a spot placed relative to the object when none is given, degrees
DEFAULT_CUTOFF_DEG = 20.0


@dataclass(frozen=True)
class PointLight:
    """Isotropic point light: intensity I (W/sr) at ``position`` (mm)."""

    position: tuple
    intensity: float = DEFAULT_INTENSITY

    def emitter_dict(self) -> dict:
        """The Mitsuba emitter of this light."""
        return {
            "type": "point",
            "position": [float(v) for v in self.position],
            "intensity": float(self.intensity),
        }

    def irradiance_scale(self, distance: float) -> float:
        """Irradiance (W/mm²) on a surface facing the light at ``distance`` mm: I / d²."""
        return float(self.intensity) / float(distance) ** 2


@dataclass(frozen=True)
class DirectionalLight:
    """Distant light: irradiance E (W/mm²) on a surface facing it, travelling along ``direction``."""

    direction: tuple
    irradiance: float = DEFAULT_IRRADIANCE

    def emitter_dict(self) -> dict:
        """The Mitsuba emitter of this light."""
        return {
            "type": "directional",
            "direction": [float(v) for v in self.direction],
            "irradiance": float(self.irradiance),
        }

    def irradiance_scale(self, distance: float) -> float:
        """Irradiance (W/mm²) on a surface facing the light: E, at any distance."""
        return float(self.irradiance)


@dataclass(frozen=True)
class SpotLight:
    """A point light at ``position`` aimed at ``target`` (mm), intensity I (W/sr) inside a cone.

    Mitsuba's falloff: full intensity within ``SPOT_BEAM_FRACTION × cutoff``, falling linearly in
    angle to 0 at ``cutoff``.
    """

    position: tuple
    target: tuple
    cutoff_deg: float = 20.0
    intensity: float = DEFAULT_INTENSITY

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

    def irradiance_scale(self, distance: float) -> float:
        """Irradiance (W/mm²) on a surface facing the light inside its cone at ``distance`` mm: I / d²."""
        return float(self.intensity) / float(distance) ** 2


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

    def radiance_at(self, directions: np.ndarray) -> np.ndarray:
        """Radiance (N, 3), W/(mm² sr), arriving from unit ``directions`` (N, 3) (pointing to the sky):
        the constant, or the map through Mitsuba's ``envmap`` (its orientation and filtering)."""
        w = np.asarray(directions, dtype=np.float64)
        if self.filename is None:
            return np.full((len(w), 3), float(self.radiance))
        mi = mitsuba()
        emitter = load_plugin(self.emitter_dict())
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*(np.ascontiguousarray(-w[:, j], dtype=np.float32) for j in range(3)))
        value = emitter.eval(si)
        return np.stack([np.asarray(value[j], dtype=np.float64) for j in range(3)], axis=1)

    def irradiance_scale(self, distance: float) -> float:
        """Irradiance (W/mm²) on an open surface (seeing half the sky) at any distance: π L, with L the
        map's mean radiance over the sphere (solid-angle weighted) times its scale."""
        if self.filename is None:
            return float(np.pi * self.radiance)
        pixels = np.asarray(mitsuba().Bitmap(str(self.filename)), dtype=np.float64)
        grey = pixels.reshape(pixels.shape[0], pixels.shape[1], -1)[..., :3].mean(axis=2)
        rows = np.sin((np.arange(grey.shape[0]) + 0.5) / grey.shape[0] * np.pi)  # a row's solid angle
        mean = float((grey.mean(axis=1) * rows).sum() / rows.sum())
        return float(np.pi * self.radiance * mean)


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


#: every form of a light's text, for the messages
FORMS = (
    "point:x,y,z[,I], spot:x,y,z,tx,ty,tz,cutoff[,I], directional:dx,dy,dz[,E] (the direction the light "
    "travels), env:L, env:MAP.exr[,scale], point@AZ,EL[,DIST[,I]], spot@AZ,EL[,DIST[,CUTOFF[,I]]] or "
    "directional@AZ,EL[,E] (AZ,EL: degrees around the object's centre, or camera or back)"
)

#: what follows the angles of a relative form, in order
_RELATIVE_TAIL = {
    "point": ("distance", "intensity"),
    "spot": ("distance", "cutoff", "intensity"),
    "directional": ("irradiance",),
}
#: the keywords that place a light along the camera's direction (towards it, or opposite it)
ANCHORS = ("camera", "back")


@dataclass(frozen=True)
class RelativeLight:
    """A point, spot or directional light placed relative to the object; :meth:`place` resolves it.

    The light lies in the direction (azimuth, elevation) from the object's centre: azimuth in degrees
    from +x towards +y, elevation in degrees above the xy plane (+z up); or along the camera's direction
    (``anchor="camera"``: from the camera's side) or opposite it (``"back"``: behind the object, seen
    from the camera).  A point or spot stands ``distance`` from the centre (mm, or object sizes with
    ``in_sizes``), a spot aimed at the centre; a directional light comes from that direction.
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
            return u if self.anchor == "camera" else -u
        az, el = np.radians(self.azimuth), np.radians(self.elevation)
        return np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])

    def place(self, placement: Placement):
        """The light in the object's frame: a :class:`PointLight`, :class:`SpotLight` or
        :class:`DirectionalLight`."""
        u = self.direction(placement)
        if self.kind == "directional":
            E = DEFAULT_IRRADIANCE if self.power is None else self.power
            return DirectionalLight(tuple(float(x) for x in -u), float(E))
        centre = np.asarray(placement.centre, dtype=np.float64)
        d = self.distance * placement.size if self.in_sizes else self.distance
        position = tuple(float(x) for x in centre + d * u)
        intensity = float(DEFAULT_INTENSITY if self.power is None else self.power)
        if self.kind == "spot":
            return SpotLight(position, tuple(float(x) for x in centre), float(self.cutoff_deg), intensity)
        return PointLight(position, intensity)


def parse_light(text: str, placement: Placement | None = None):
    """A light from its text.

    In the object's frame (mm, +z up): ``point:x,y,z[,I]``, ``spot:x,y,z,tx,ty,tz,cutoff_deg[,I]`` (at
    x,y,z aimed at tx,ty,tz), ``directional:dx,dy,dz[,E]`` (dx,dy,dz: the direction the light
    *travels*, so ``0,0,-1`` shines down), ``env:L`` (constant sky) or ``env:MAP.exr[,scale]``
    (environment map).  Relative to the object: ``point@AZ,EL[,DIST[,I]]``,
    ``spot@AZ,EL[,DIST[,CUTOFF[,I]]]`` (aimed at the centre) and ``directional@AZ,EL[,E]`` (coming
    *from* AZ,EL) — AZ, EL in degrees (:class:`RelativeLight`), or ``camera`` / ``back`` in their place;
    DIST in mm, or object sizes with a trailing ``x`` (``2x``; default :data:`DEFAULT_DISTANCE`).

    A relative light is resolved against ``placement``; without one it is returned as a
    :class:`RelativeLight` (its text checked), to be placed with :func:`place_light`.

    Examples
    --------
    >>> parse_light("point:0,0,100,5e3")
    PointLight(position=(0.0, 0.0, 100.0), intensity=5000.0)
    >>> box = Placement(((-10.0, -10.0, 0.0), (10.0, 10.0, 20.0)))
    >>> parse_light("point@90,0,50,1e3", box)
    PointLight(position=(3.061616997868383e-15, 50.0, 10.0), intensity=1000.0)
    >>> parse_light("directional@0,90", box)
    DirectionalLight(direction=(-6.123233995736766e-17, -0.0, -1.0), irradiance=1.0)
    """
    kind, at, rest = text.partition("@")
    if at and ":" not in kind:
        light = _relative(text, kind.strip(), rest)
        return light if placement is None else light.place(placement)
    kind, _, rest = text.partition(":")
    if kind == "env" and rest:
        try:
            float(rest.split(",")[0])
        except ValueError:  # not a number: the name of an environment map
            return _environment_map(rest)
    counts = {"point": (3, 4), "directional": (3, 4), "spot": (7, 8), "env": (1,)}
    if kind not in counts:
        raise TranslucencyError(f"light: unknown kind {kind!r} in {text!r}; expected {FORMS}")
    parts = rest.split(",")
    if len(parts) not in counts[kind]:
        raise TranslucencyError(
            f"light: {kind}: takes {' or '.join(map(str, counts[kind]))} numbers, got {len(parts)} in "
            f"{text!r}; expected {FORMS}"
        )
    v = [_number(text, f"number {k + 1}", p) for k, p in enumerate(parts)]
    power = {"point": 3, "directional": 3, "spot": 7, "env": 0}[kind]
    if len(v) > power and v[power] < 0:
        raise TranslucencyError(f"light: the intensity of {text!r} must be >= 0")
    if len(v) > power and v[power] > MAX_POWER:
        raise TranslucencyError(f"light: the intensity of {text!r} must be at most {MAX_POWER:g}")
    if max((abs(x) for x in v[:power]), default=0.0) > MAX_COORDINATE:
        raise TranslucencyError(
            f"light: positions and directions of {text!r} must lie within ±{MAX_COORDINATE:g}"
        )
    if kind == "spot" and np.allclose(v[:3], v[3:6]):
        raise TranslucencyError(f"light: the spot in {text!r} is aimed at its own position")
    if kind == "spot" and not MIN_CUTOFF_DEG <= v[6] < 90:
        raise TranslucencyError(
            f"light: the spot's cutoff angle in {text!r} must lie in [{MIN_CUTOFF_DEG:g}, 90) degrees"
        )
    if kind == "point":
        return PointLight(tuple(v[:3]), *(v[3:] or []))
    if kind == "directional":
        d = np.asarray(v[:3])
        if not np.linalg.norm(d) > 0:
            raise TranslucencyError("light: a directional light needs a non-zero direction")
        return DirectionalLight(tuple(float(x) for x in d / np.linalg.norm(d)), *(v[3:] or []))
    if kind == "spot":
        return SpotLight(tuple(v[:3]), tuple(v[3:6]), *v[6:])
    return EnvironmentLight(v[0])


def place_light(light, placement: Placement):
    """``light`` in the object's frame: a :class:`RelativeLight` placed, any other light as it is."""
    return light.place(placement) if isinstance(light, RelativeLight) else light


def _number(text: str, what: str, part: str) -> float:
    """One finite number of a light's text, or one line naming the part at fault."""
    try:
        x = float(part)
    except ValueError:
        raise TranslucencyError(f"light: the {what} {part.strip()!r} of {text!r} is not a number") from None
    if not np.isfinite(x):
        raise TranslucencyError(f"light: every number must be finite, got {part.strip()!r} in {text!r}")
    return x


def _relative(text: str, kind: str, rest: str) -> RelativeLight:
    """``KIND@AZ,EL[,…]`` or ``KIND@camera|back[,…]``: checked part by part."""
    if kind not in _RELATIVE_TAIL:
        raise TranslucencyError(
            f"light: {kind!r} cannot be placed relative to the object in {text!r} (point, spot or "
            f"directional can); expected {FORMS}"
        )
    parts = [p.strip() for p in rest.split(",")]
    fields: dict = {"kind": kind}
    if parts[0] in ANCHORS:
        fields["anchor"], tail = parts[0], parts[1:]
    else:
        if len(parts) < 2:
            raise TranslucencyError(
                f"light: {kind}@ needs an azimuth and an elevation (degrees) or camera or back, got {text!r}"
            )
        fields["azimuth"] = _number(text, "azimuth", parts[0])
        fields["elevation"] = _number(text, "elevation", parts[1])
        if not -90.0 <= fields["elevation"] <= 90.0:
            raise TranslucencyError(
                f"light: the elevation {parts[1]!r} of {text!r} must lie in [-90, 90] degrees"
            )
        tail = parts[2:]
    names = _RELATIVE_TAIL[kind]
    if len(tail) > len(names):
        raise TranslucencyError(
            f"light: {text!r} has {len(tail)} values after the direction; {kind}@ takes at most "
            f"{len(names)} ({', '.join(names)})"
        )
    for name, part in zip(names, tail):
        if name == "distance":
            in_sizes = part.lower().endswith("x")
            d = _number(text, "distance", part[:-1] if in_sizes else part)
            if not 0 < d <= MAX_COORDINATE:
                raise TranslucencyError(
                    f"light: the distance {part!r} of {text!r} must be > 0 and at most {MAX_COORDINATE:g}"
                )
            fields.update(distance=d, in_sizes=in_sizes)
        elif name == "cutoff":
            c = _number(text, "cutoff angle", part)
            if not MIN_CUTOFF_DEG <= c < 90:
                raise TranslucencyError(
                    f"light: the spot's cutoff angle {part!r} in {text!r} must lie in "
                    f"[{MIN_CUTOFF_DEG:g}, 90) degrees"
                )
            fields["cutoff_deg"] = c
        else:
            p = _number(text, name, part)
            if not 0 <= p <= MAX_POWER:
                raise TranslucencyError(
                    f"light: the {name} {part!r} of {text!r} must be >= 0 and at most {MAX_POWER:g}"
                )
            fields["power"] = p
    return RelativeLight(**fields)


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
