"""A light from its text (:func:`parse_light`): ``point:x,y,z[,I]``, ``spot:…``, ``directional:…``,
``env:…`` in the object's frame, or ``KIND@AZ,EL[,…]`` relative to it; every message lists the forms
(:data:`FORMS`)."""

from __future__ import annotations

from ..._validate import TranslucencyError
from .light import ANCHORS, KINDS, MAX_COORDINATE, MAX_POWER, MIN_CUTOFF_DEG, Light, forms, number
from .placement import Placement, RelativeLight

#: every form of a light's text, for the messages (the kinds are registered: the package imports them first)
FORMS = forms()


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
    if kind not in KINDS:
        raise TranslucencyError(f"light: unknown kind {kind!r} in {text!r}; expected {FORMS}")
    return KINDS[kind].parse(text, rest)


def place_light(light, placement: Placement) -> Light:
    """``light`` in the object's frame: a :class:`RelativeLight` placed, any other light as it is."""
    return light.place(placement)


def _relative(text: str, kind: str, rest: str) -> RelativeLight:
    """``KIND@AZ,EL[,…]`` or ``KIND@camera|back[,…]``: checked part by part."""
    cls = KINDS.get(kind)
    if cls is None or not cls.relative_tail:
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
        fields["azimuth"] = number(text, "azimuth", parts[0])
        fields["elevation"] = number(text, "elevation", parts[1])
        if not -90.0 <= fields["elevation"] <= 90.0:
            raise TranslucencyError(
                f"light: the elevation {parts[1]!r} of {text!r} must lie in [-90, 90] degrees"
            )
        tail = parts[2:]
    names = cls.relative_tail
    if len(tail) > len(names):
        raise TranslucencyError(
            f"light: {text!r} has {len(tail)} values after the direction; {kind}@ takes at most "
            f"{len(names)} ({', '.join(names)})"
        )
    for name, part in zip(names, tail):
        if name == "distance":
            in_sizes = part.lower().endswith("x")
            d = number(text, "distance", part[:-1] if in_sizes else part)
            if not 0 < d <= MAX_COORDINATE:
                raise TranslucencyError(
                    f"light: the distance {part!r} of {text!r} must be > 0 and at most {MAX_COORDINATE:g}"
                )
            fields.update(distance=d, in_sizes=in_sizes)
        elif name == "cutoff":
            c = number(text, "cutoff angle", part)
            if not MIN_CUTOFF_DEG <= c < 90:
                raise TranslucencyError(
                    f"light: the spot's cutoff angle {part!r} in {text!r} must lie in "
                    f"[{MIN_CUTOFF_DEG:g}, 90) degrees"
                )
            fields["cutoff_deg"] = c
        else:
            p = number(text, name, part)
            if not 0 <= p <= MAX_POWER:
                raise TranslucencyError(
                    f"light: the {name} {part!r} of {text!r} must be >= 0 and at most {MAX_POWER:g}"
                )
            fields["power"] = p
    return RelativeLight(**fields)
