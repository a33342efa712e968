"""The light transport of a fitted object: one room, from the choices to the prepared object.

:mod:`.options` (the choices, :class:`TransportOptions`) → :mod:`.kinds` (the variants behind one
protocol, :func:`register_transport`) → :mod:`.parameters` (per vertex, blended from the fit) →
:mod:`.matrices` (the sparse near matrices, :func:`default_radius`) and :mod:`._far_field` →
:mod:`.irradiance` (light in, per vertex) → :mod:`.relight` (radiance per vertex) and :mod:`.lean` (its
tilt toward the light) → :mod:`.prepared` (:class:`PreparedObject`: what every renderer draws) →
:mod:`.transfer` and :mod:`.sh` (its precomputed form for the viewer).
"""

from .irradiance import vertex_irradiance
from .kinds import TRANSPORTS, TransportKind, register_transport, transport_kind
from .matrices import MAX_PAIRS, default_radius, transport_matrices
from .options import TransportOptions
from .prepared import PreparedObject
from .relight import Transport, relight_object, relight_vertices

__all__ = [
    "MAX_PAIRS",
    "PreparedObject",
    "TRANSPORTS",
    "Transport",
    "TransportKind",
    "TransportOptions",
    "default_radius",
    "register_transport",
    "relight_object",
    "relight_vertices",
    "transport_kind",
    "transport_matrices",
    "vertex_irradiance",
]
