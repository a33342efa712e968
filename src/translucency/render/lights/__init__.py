r"""Lights of a rendering: point, spot, directional and environment (constant sky or map), each one class
behind one protocol, :class:`Light`.

A light answers everything the renderer asks of it, so that the rest of ``render/`` never tells kinds
apart and a new kind of light is one class — one module of this package (:mod:`.point`, :mod:`.spot`,
:mod:`.directional`, :mod:`.environment`), registered in :data:`KINDS` by stating its text's prefix:

- :meth:`Light.irradiance_at`: the irradiance E (W/mm²) it brings to points with their normals, with
  shadow rays traced by Mitsuba (``ray_test``), behind a boundary weighted by
  :math:`F_t(\theta_i)/F_t(0)` and with an incidence law per channel
  (:mod:`translucency.transport.irradiance` states the integral);
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
camera: :mod:`.placement`); the text of every kind is read in :mod:`.text`, the protocol and the bounds of a
light's numbers are in :mod:`.light`.

Units: point and spot intensity I in W/sr, directional irradiance E in W/mm²,
environment radiance L in W/(mm² sr).
"""

# the kinds register in the order the messages list them: point, spot, directional, environment
from .light import (
    ANCHORS,
    DEFAULT_CUTOFF_DEG,
    DEFAULT_DISTANCE,
    DEFAULT_INTENSITY,
    DEFAULT_IRRADIANCE,
    DEFAULT_LIGHT,
    KEY_RAISE_DEG,
    KEY_TURN_DEG,
    KINDS,
    MAX_COORDINATE,
    MAX_POWER,
    MIN_CUTOFF_DEG,
    Light,
)

from .point import PointLight  # isort: skip
from .spot import SpotLight  # isort: skip
from .directional import DirectionalLight  # isort: skip
from .environment import EnvironmentLight  # isort: skip
from .placement import Placement, RelativeLight  # isort: skip
from .text import FORMS, parse_light, place_light  # isort: skip

__all__ = [
    "ANCHORS",
    "DEFAULT_CUTOFF_DEG",
    "DEFAULT_DISTANCE",
    "DEFAULT_INTENSITY",
    "DEFAULT_IRRADIANCE",
    "DEFAULT_LIGHT",
    "KEY_RAISE_DEG",
    "KEY_TURN_DEG",
    "FORMS",
    "KINDS",
    "MAX_COORDINATE",
    "MAX_POWER",
    "MIN_CUTOFF_DEG",
    "DirectionalLight",
    "EnvironmentLight",
    "Light",
    "Placement",
    "PointLight",
    "RelativeLight",
    "SpotLight",
    "parse_light",
    "place_light",
]
