r"""The transports a fitted object can be drawn with: one object per variant behind one protocol.

A *kind* turns a per-vertex model on its mesh into the prepared :class:`~.relight.Transport` — the
linear map from the irradiance E (W/mm², per vertex) to the radiance L (W/(mm² sr), per vertex) that
every renderer applies, :math:`L_\lambda = T_\lambda E`.  Two ship:

- ``default`` (:class:`MeasuredTransport`): the fitted profiles between every pair of vertices within the
  near radius and through the hierarchical far field beyond it, with what the acquisition measured and the
  fit cannot represent — each vertex's own area and total, and the through-body table (light between
  sides whose normals face apart, :mod:`translucency.model.through`) where the model holds one;
- ``paper`` (:data:`PAPER`, the same class without the table): the paper's model alone, each incident
  point's radial profile.

A new transport is one more class with ``name``, ``summary``, ``incidence`` and ``build`` passed to
:func:`register_transport`; every renderer draws it by name (``TransportOptions(kind=NAME)``), none
changes (docs/architecture.md, "How to add a transport").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from .._validate import TranslucencyError
from ..model.incidence import INCIDENCE_LAWS
from .matrices import transport_matrices
from .walk import WalkedTransport


class TransportKind(Protocol):
    """What a transport variant is: a name, one line on what it draws, and how it is built."""

    #: the name ``TransportOptions(kind=...)`` takes
    name: str
    #: one line on what it draws (renderers' summaries and ``--help`` state it)
    summary: str
    #: how light arriving at an angle counts against the normal-incidence data
    #: (:data:`~translucency.model.incidence.INCIDENCE_LAWS`)
    incidence: str

    def build(self, model, mesh, *, radius: float, shrink: bool, max_pairs: float):
        """The prepared :class:`~translucency.transport.relight.Transport` of ``model`` on ``mesh`` at the
        near radius ``radius`` mm (``shrink``: the radius is the default and may shrink until the pairs fit
        ``max_pairs``)."""
        ...


@dataclass(frozen=True)
class MeasuredTransport:
    """The fitted profiles with the measured near field, and the through-body table where the model holds
    one (``through=None``) or never (``through=False``: the paper's model)."""

    name: str = "default"
    summary: str = "fitted per-vertex model + through-body table"
    incidence: str = "half-space"
    through: bool | None = None

    def build(self, model, mesh, *, radius: float, shrink: bool, max_pairs: float):
        """:func:`~.matrices.transport_matrices` with this kind's table."""
        return transport_matrices(
            model, mesh, radius=radius, shrink=shrink, max_pairs=max_pairs, through=self.through
        )


#: the paper's model: each incident point's radial profile, no through-body table
PAPER = MeasuredTransport(name="paper", summary="fitted per-vertex model (the paper's)", through=False)

#: the transports by name: the two that ship and any registered since
TRANSPORTS: dict[str, TransportKind] = {k.name: k for k in (MeasuredTransport(), PAPER, WalkedTransport())}


def register_transport(kind: TransportKind) -> TransportKind:
    """Make ``kind`` drawable by its name in every renderer; returns it.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> from translucency import register_transport
    >>> from translucency.transport import TRANSPORTS
    >>> from translucency.transport.kinds import MeasuredTransport
    >>> @dataclass(frozen=True)
    ... class Dimmer:  # the default at half its strength
    ...     name: str = "dimmer"
    ...     summary: str = "the default, halved"
    ...     incidence: str = "half-space"
    ...     def build(self, model, mesh, **near):
    ...         T = MeasuredTransport().build(model, mesh, **near)
    ...         return T  # (a real variant would change T here)
    >>> register_transport(Dimmer()).name in TRANSPORTS
    True
    >>> del TRANSPORTS["dimmer"]
    """
    missing = [a for a in ("name", "summary", "incidence", "build") if not hasattr(kind, a)]
    if missing:
        raise TranslucencyError(f"transport: {kind!r} has no {', '.join(missing)}")
    if kind.incidence not in INCIDENCE_LAWS:
        raise TranslucencyError(
            f"transport {kind.name}: incidence {kind.incidence!r} is not one of {', '.join(INCIDENCE_LAWS)}"
        )
    TRANSPORTS[kind.name] = kind
    return kind


def transport_kind(name: str) -> TransportKind:
    """The registered transport ``name``, or one line naming the known ones."""
    if name not in TRANSPORTS:
        raise TranslucencyError(f"transport: {name!r} is not one of {', '.join(TRANSPORTS)}")
    return TRANSPORTS[name]
