r"""Lights of a rendering: point, spot, directional and environment (constant sky or map), each one class
behind one protocol, :class:`Light`.

A light answers everything the renderer asks of it, so that the rest of ``render/`` never tells kinds
apart and a new kind of light is one class here:

- :meth:`Light.irradiance_at`: the irradiance E (W/mm²) it brings to points with their normals, with
  shadow rays traced by Mitsuba (``ray_test``), behind a boundary weighted by
  :math:`F_t(\theta_i)/F_t(0)` and with an incidence law per channel
  (:mod:`translucency.render.irradiance` states the integral);
- :meth:`Light.sh_coefficients`: its projection on the real spherical harmonics (:mod:`.sh`), for a
  :attr:`~Light.distant` light — one that is the same at every point;
- :attr:`Light.delta`: whether it arrives along one direction at a point (sharp shadows; unseen in a
  smooth reflection; unreachable through a delta refraction, so no ``volpath`` reference behind a
  dielectric);
- :meth:`Light.emitter_dict`: its Mitsuba emitter, used alike for our picture and for the ``volpath``
  reference, so the conventions live in one place; :meth:`Light.irradiance_scale`: the irradiance it
  brings at a stated distance (the scale of a fixed exposure);
- :meth:`Light.parse` (from its text, through :func:`parse_light`), :meth:`Light.placed` (placed
  relative to the object), :meth:`Light.place` and :meth:`Light.record` (its JSON record).

The spot's falloff is Mitsuba's (:data:`translucency.mitsuba.SPOT_BEAM_FRACTION`).  Positions and
directions are in the object's frame (mm, +z up); a light may also be placed relative to the object
(``point@AZ,EL,DIST``: azimuth and elevation around the object's centre, a distance from it), resolved by
:class:`RelativeLight` against a :class:`Placement` (the object's bounds and the direction towards the
camera).

Units: point and spot intensity I in W/sr, directional irradiance E in W/mm²,
environment radiance L in W/(mm² sr).
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from .._validate import TranslucencyError, plain
from ..geometry import tangent_frames
from ..mitsuba import SPOT_BEAM_FRACTION, drjit, load_plugin, mitsuba, rays, spot_dict
from ..model.boundary import fresnel_transmittance
from . import sh

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


#: every kind of light by the word its text begins with (``point:``, ``env:``), in the order the messages
#: list them; a :class:`Light` subclass that states its :attr:`~Light.prefix` is one
KINDS: dict[str, type[Light]] = {}
#: the keywords that place a light along the camera's direction (towards it, or opposite it)
ANCHORS = ("camera", "back")


class Light(ABC):
    """What every light answers (module docstring): one subclass per kind, a frozen dataclass in mm and W."""

    #: its kind in records and messages ("point", "spot", "directional", "environment")
    kind: ClassVar[str]
    #: the word its text begins with (``point:…``); stating it registers the kind in :data:`KINDS`
    prefix: ClassVar[str]
    #: its text's forms, for the messages (:data:`FORMS`)
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
                f"in {text!r}; expected {FORMS}"
            )
        v = [_number(text, f"number {k + 1}", p) for k, p in enumerate(parts)]
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
    def placed(cls, relative: RelativeLight, placement: Placement) -> Light:
        """The light that ``relative`` describes, in the object's frame (a kind with a
        :attr:`relative_tail`)."""
        raise TypeError(f"a {cls.__name__} cannot be placed relative to the object")

    def place(self, placement: Placement) -> Light:
        """The light in the object's frame: itself (a :class:`RelativeLight` resolves there)."""
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
        (:func:`translucency.render.irradiance.vertex_irradiance`)."""

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
    """Isotropic point light: intensity I (W/sr) at ``position`` (mm)."""

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
        return cls(position, relative.power_or(DEFAULT_INTENSITY))

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


@dataclass(frozen=True)
class SpotLight(_DeltaLight):
    """A point light at ``position`` aimed at ``target`` (mm), intensity I (W/sr) inside a cone.

    Mitsuba's falloff: full intensity within ``SPOT_BEAM_FRACTION × cutoff``, falling linearly in
    angle to 0 at ``cutoff``.
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
        intensity = relative.power_or(DEFAULT_INTENSITY)
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


@dataclass(frozen=True)
class EnvironmentLight(Light):
    """Light from every direction: a constant radiance L (W/(mm² sr)), or an environment map.

    With ``filename`` a latitude–longitude image (EXR, HDR, PNG; linear RGB) read by
    Mitsuba's ``envmap`` emitter, scaled by ``radiance``; the map's up axis (+Y)
    is turned to the scene's +Z, the same for the irradiance, our picture and
    the reference.
    """

    kind = "environment"
    prefix = "env"
    forms = "env:L, env:MAP.exr[,scale]"
    counts, power_index = (1,), 0
    distant = True
    delta = False

    radiance: float = 0.1
    samples: int = 64  # visibility rays per vertex (cosine-weighted, or by the map's importance)
    filename: str | None = None

    @classmethod
    def parse(cls, text: str, rest: str) -> EnvironmentLight:
        """``env:L`` or ``env:MAP[,scale]`` (a first part that is not a number names a map)."""
        if rest:
            try:
                float(rest.split(",")[0])
            except ValueError:  # not a number: the name of an environment map
                return _environment_map(rest)
        return super().parse(text, rest)

    @classmethod
    def of_numbers(cls, text: str, v: list) -> EnvironmentLight:
        return cls(v[0])

    def emitter_dict(self) -> dict:
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

    def irradiance_at(self, scene, x, n, extent: float, eta: float = 1.0, incidence=None) -> np.ndarray:
        r"""Estimate :math:`E = \int L(\omega) V(\omega) \cos\theta\, F(\cos\theta)\, d\omega` with K =
        :attr:`samples` rays per point (F: the incidence law's factor, 1 without one).

        Constant sky: cosine-weighted directions, :math:`E \approx \pi L \langle V F \rangle`.
        Map: directions drawn by the ``envmap`` emitter in proportion to its luminance,
        :math:`E \approx \langle (L/p)\, V \cos^+\theta\, F \rangle` (RGB).
        """
        mi = mitsuba()
        K = int(self.samples)
        rng = np.random.default_rng(0)
        u1, u2 = rng.random((2, len(x), K))
        o = np.repeat(x + n * 5e-4 * extent, K, axis=0)
        if self.filename is None:
            r, phi = np.sqrt(u1), 2 * np.pi * u2
            local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u1)], axis=-1)  # cosine-weighted
            frame = tangent_frames(n)  # rows t, b, n
            w = np.einsum("vkj,vji->vki", local, frame).reshape(-1, 3)
            weight = np.full((len(w), 1), np.pi * self.radiance)  # L cos / p with p = cos/π
        else:
            emitter = load_plugin(self.emitter_dict())
            it = drjit().zeros(mi.Interaction3f, len(o))
            it.p = mi.Point3f(*(o[:, j].astype(np.float32) for j in range(3)))
            ds, spec = emitter.sample_direction(
                it, mi.Point2f(u1.ravel().astype(np.float32), u2.ravel().astype(np.float32))
            )
            w = np.stack([np.asarray(ds.d.x), np.asarray(ds.d.y), np.asarray(ds.d.z)], axis=1).astype(
                np.float64
            )
            weight = np.stack([np.asarray(spec[j]) for j in range(3)], axis=1)  # L / p, times cos⁺ below
        cos_i = np.einsum("vkj,vj->vk", w.reshape(len(x), K, 3), n).reshape(-1)
        if self.filename is not None:
            weight = weight * np.maximum(cos_i, 0.0)[:, None]
        open_sky = ~np.asarray(scene.ray_test(rays(o, w)))
        weight = (
            weight * (open_sky * fresnel_transmittance(cos_i, eta) / fresnel_transmittance(1.0, eta))[:, None]
        )
        weight = weight.reshape(len(x), K, -1)
        F = None if incidence is None else incidence.factor(cos_i.reshape(len(x), K))  # (V, K, 3)
        if F is not None:
            return (weight * F).mean(axis=1)
        E = weight.mean(axis=1)
        return E[:, 0] if self.filename is None else E

    def sh_coefficients(self, bands: int) -> np.ndarray:
        r""":math:`L_k = \int L\, Y_k\, d\omega` over :meth:`radiance_at` (:func:`.sh.project_environment`,
        a Fibonacci lattice's quadrature)."""
        return sh.project_environment(self.radiance_at, bands)


def _forms() -> str:
    """Every form of a light's text, for the messages: each kind's, then those relative to the object."""
    relative = [cls.relative_form for cls in KINDS.values() if cls.relative_form]
    return (
        f"{', '.join(cls.forms for cls in KINDS.values())}, {', '.join(relative[:-1])} or {relative[-1]} "
        "(AZ,EL: degrees around the object's centre, or camera or back)"
    )


#: every form of a light's text, for the messages
FORMS = _forms()


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

    def position(self, placement: Placement) -> tuple[tuple, np.ndarray]:
        """A point's or spot's position (mm) ``distance`` from the object's centre towards the light, and
        the centre."""
        u = self.direction(placement)
        centre = np.asarray(placement.centre, dtype=np.float64)
        d = self.distance * placement.size if self.in_sizes else self.distance
        return tuple(float(x) for x in centre + d * u), centre

    def power_or(self, default: float) -> float:
        """Its power, or ``default`` where its text gave none."""
        return float(default if self.power is None else self.power)

    def place(self, placement: Placement) -> Light:
        """The light in the object's frame: its kind's :meth:`Light.placed`."""
        return KINDS[self.kind].placed(self, placement)


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
        fields["azimuth"] = _number(text, "azimuth", parts[0])
        fields["elevation"] = _number(text, "elevation", parts[1])
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
