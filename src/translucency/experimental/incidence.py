"""The incidence law's ablations as transports of their own: drawn by name in every renderer
(``TransportOptions(kind="half-space-in")``) once this module is imported.

- ``half-space-in``: the half-space law on the light in only, a Lambertian exit;
- ``normal-incidence``: every direction counted as the data's normal-incidence beams.

They exist for ``benchmarks/objects_table.py``'s comparison (docs/incidence.md); unstable.
"""

from __future__ import annotations

from ..transport.kinds import MeasuredTransport, register_transport

#: the ablations, registered on import
HALF_SPACE_IN = register_transport(
    MeasuredTransport(
        name="half-space-in",
        summary="fitted per-vertex model + through-body table, half-space law on the light in only",
        incidence="half-space-in",
    )
)
NORMAL_INCIDENCE = register_transport(
    MeasuredTransport(
        name="normal-incidence",
        summary="fitted per-vertex model + through-body table, every direction as the normal beams",
        incidence="normal",
    )
)
