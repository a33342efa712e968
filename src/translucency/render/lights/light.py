"""The protocol every light answers (:class:`Light`), the bounds and defaults of a light's numbers, and
the registry of kinds by the word their text begins with (:data:`KINDS`).

Units: point and spot intensity I in W/sr, directional irradiance E in W/mm², environment radiance L in
W/(mm² sr); positions in mm.
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from typing import ClassVar

import numpy as np

from ..._validate import TranslucencyError
from ...mitsuba import rays
from ...model.boundary import fresnel_transmittance

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
#: the power of a light when none is given: I of a point or spot at a position in mm (W/sr), E of a
#: directional light (W/mm²).  A point or spot placed relative to the object gets the I that brings
#: DEFAULT_IRRADIANCE to the object's centre from where it stands (I = E d², d its distance in mm), so the
#: default light lights a 10 mm bead and a 1 m statue alike
DEFAULT_INTENSITY = 1.0e4
DEFAULT_IRRADIANCE = 1.0
#: the ``key`` anchor: the camera's direction turned this many degrees about +z (counter-clockwise seen
#: from above) and raised this many degrees, so the light stands beside and above the camera
KEY_TURN_DEG, KEY_RAISE_DEG = 28.0, 20.0
#: the light of ``render``, ``export`` and the Python functions when none is given: a point light
#: beside and above the camera, 1.5 object sizes from the centre, bringing 1 W/mm² there — placed
#: relative to the object and the view, so every object at any scale and from any view is lit from the
#: front; with the ``fixed`` exposure (render/tonemap.py) its picture is exposed alike
DEFAULT_LIGHT = "point@key"
#: the cone of a spot placed relative to the object when none is given, degrees
DEFAULT_CUTOFF_DEG = 20.0


#: every kind of light by the word its text begins with (``point:``, ``env:``), in the order the messages
#: list them; a :class:`Light` subclass that states its :attr:`~Light.prefix` is one
KINDS: dict[str, type[Light]] = {}
#: the keywords that place a light by the camera's direction: at the camera, opposite it (behind the
#: object), or beside and above it (KEY_TURN_DEG, KEY_RAISE_DEG)
ANCHORS = ("camera", "back", "key")


class Light(ABC):
    """What every light answers (module docstring): one subclass per kind, a frozen dataclass in mm and W.

    Examples
    --------
    >>> from translucency.render.lights import EnvironmentLight, PointLight
    >>> {prefix: kind.__name__ for prefix, kind in KINDS.items()}  # registered by stating their prefix
    {'point': 'PointLight', 'spot': 'SpotLight', 'directional': 'DirectionalLight', 'env': 'EnvironmentLight'}
    >>> [(kind.delta, kind.distant) for kind in KINDS.values()]
    [(True, False), (True, False), (True, True), (False, True)]
    >>> lamp = PointLight((0.0, 0.0, 50.0))
    >>> isinstance(lamp, Light), lamp.record()
    (True, {'kind': 'point', 'position': (0.0, 0.0, 50.0), 'intensity': 10000.0})
    >>> EnvironmentLight(0.5).sh_coefficients(1).round(4)  # L_00 = ∫ L Y_00 dω = 2 √π L
    array([[1.7725, 1.7725, 1.7725]])
    >>> lamp.sh_coefficients(1)
    Traceback (most recent call last):
    ...
    TypeError: a PointLight is not distant: no transfer (point and spot lights relight)
    """

    #: its kind in records and messages ("point", "spot", "directional", "environment")
    kind: ClassVar[str]
    #: the word its text begins with (``point:…``); stating it registers the kind in :data:`KINDS`
    prefix: ClassVar[str]
    #: its text's forms, for the messages (:func:`forms`)
    forms: ClassVar[str]
    #: how many numbers its text ``prefix:a,b,…`` takes, and which of them is its power
    counts: ClassVar[tuple[int, ...]]
    power_index: ClassVar[int]
    #: what follows the angles of its form relative to the object (``prefix@AZ,EL,…``), in order, and that
    #: form; () and None: it cannot be placed relative to the object
    relative_tail: ClassVar[tuple[str, ...]] = ()
    relative_form: ClassVar[str | None] = None
    #: infinitely far: the same at every point, so it has spherical-harmonic coefficients; a light that is
    #: not distant stands at a ``position`` (mm)
    distant: ClassVar[bool]
    #: it arrives along one direction at a point (module docstring)
    delta: ClassVar[bool]

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "prefix" in cls.__dict__:
            KINDS[cls.prefix] = cls

    @classmethod
    def parse(cls, text: str, rest: str) -> Light:
        """The light of ``text`` (``prefix:rest``): its numbers checked, then :meth:`of_numbers`."""
        parts = rest.split(",")
        if len(parts) not in cls.counts:
            raise TranslucencyError(
                f"light: {cls.prefix}: takes {' or '.join(map(str, cls.counts))} numbers, got {len(parts)} "
                f"in {text!r}; expected {forms()}"
            )
        v = [number(text, f"number {k + 1}", p) for k, p in enumerate(parts)]
        power = cls.power_index
        if len(v) > power and v[power] < 0:
            raise TranslucencyError(f"light: the intensity of {text!r} must be >= 0")
        if len(v) > power and v[power] > MAX_POWER:
            raise TranslucencyError(f"light: the intensity of {text!r} must be at most {MAX_POWER:g}")
        if max((abs(x) for x in v[:power]), default=0.0) > MAX_COORDINATE:
            raise TranslucencyError(
                f"light: positions and directions of {text!r} must lie within ±{MAX_COORDINATE:g}"
            )
        return cls.of_numbers(text, v)

    @classmethod
    @abstractmethod
    def of_numbers(cls, text: str, v: list) -> Light:
        """The light of its text's numbers ``v`` (finite; the power and coordinates within bounds)."""

    @classmethod
    def placed(cls, relative, placement) -> Light:
        """The light that ``relative`` (a :class:`~.placement.RelativeLight`) describes, in the object's
        frame (a kind with a :attr:`relative_tail`); ``placement``: a :class:`~.placement.Placement`."""
        raise TypeError(f"a {cls.__name__} cannot be placed relative to the object")

    def place(self, placement) -> Light:
        """The light in the object's frame (``placement``: a :class:`~.placement.Placement`): itself (a
        :class:`~.placement.RelativeLight` resolves there)."""
        return self

    @abstractmethod
    def emitter_dict(self) -> dict:
        """The Mitsuba emitter of this light."""

    @abstractmethod
    def irradiance_scale(self, distance: float) -> float:
        """Irradiance (W/mm²) it brings to a surface facing it at ``distance`` mm."""

    @abstractmethod
    def irradiance_at(self, scene, x, n, extent: float, eta: float = 1.0, incidence=None) -> np.ndarray:
        r"""Irradiance E (W/mm²) at points ``x`` (N, 3) with unit normals ``n``, shadowed by Mitsuba's
        ``scene`` (rays leave a fraction of ``extent``, the object's largest extent in mm, off the
        surface): (N,), or (N, 3) for an environment map or with an ``incidence`` law; with ``eta`` ≠ 1
        each arriving direction weighted by :math:`F_t(\theta_i)/F_t(0)`
        (:func:`translucency.transport.irradiance.vertex_irradiance`)."""

    def sh_coefficients(self, bands: int) -> np.ndarray:
        """Its coefficients (K, 3) on the first ``bands`` bands of real spherical harmonics (:mod:`.sh`)."""
        raise TypeError(
            f"a {type(self).__name__} is not distant: no transfer (point and spot lights relight)"
        )

    def record(self) -> dict:
        """The light as JSON: its kind and its parameters."""
        return {"kind": self.kind, **dataclasses.asdict(self)}


class _DeltaLight(Light):
    """A light arriving along one direction at a point: its unshadowed irradiance and direction
    (:meth:`arrival`), then one shadow ray per point."""

    delta = True

    @abstractmethod
    def arrival(self, scene, x, n) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r"""(w, E, t): the unit direction towards the light (N, 3), the unshadowed irradiance
        :math:`E = I\,\cos^+\theta_i / d^2` or :math:`E\cos^+\theta_i` (N,), W/mm², and how far a
        shadow ray goes (N,), mm."""

    def irradiance_at(self, scene, x, n, extent: float, eta: float = 1.0, incidence=None) -> np.ndarray:
        w, E, t_max = self.arrival(scene, x, n)
        eps = 1e-4 * extent
        o = x + n * eps * 5
        blocked = np.asarray(scene.ray_test(rays(o, w, t_max - 10 * eps)))
        cos_i = np.einsum("vk,vk->v", w, n)
        E = E * fresnel_transmittance(cos_i, eta) / fresnel_transmittance(1.0, eta)
        E = np.where(blocked | (E <= 0), 0.0, E)
        F = None if incidence is None else incidence.factor(cos_i)  # (V, 3) or None
        return E if F is None else E[:, None] * F


def number(text: str, what: str, part: str) -> float:
    """One finite number of a light's text, or one line naming the part at fault."""
    try:
        x = float(part)
    except ValueError:
        raise TranslucencyError(f"light: the {what} {part.strip()!r} of {text!r} is not a number") from None
    if not np.isfinite(x):
        raise TranslucencyError(f"light: every number must be finite, got {part.strip()!r} in {text!r}")
    return x


def forms() -> str:
    """Every form of a light's text, for the messages: each kind's, then those relative to the object."""
    relative = [cls.relative_form for cls in KINDS.values() if cls.relative_form]
    return (
        f"{', '.join(cls.forms for cls in KINDS.values())}, {', '.join(relative[:-1])} or {relative[-1]} "
        "(AZ,EL: degrees around the object's centre, or camera or back)"
    )
