"""How a fitted object's light transport is drawn: the one set of choices every renderer takes.

:class:`TransportOptions` is built once where the user's options enter (a command, a library function)
and travels whole to :class:`~translucency.transport.PreparedObject`; nothing below it takes the choices
one by one.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .._validate import TranslucencyError, check_option
from .kinds import transport_kind
from .matrices import MAX_PAIRS


@dataclass(frozen=True)
class TransportOptions:
    """The transport's choices, checked once (here).

    Parameters
    ----------
    kind : str
        The transport variant (:data:`~translucency.transport.kinds.TRANSPORTS`): ``default`` (the model's
        measured near field and its through-body table) or ``paper`` (the paper's model alone).
    radius : float, optional
        Near radius, mm: pairs within it summed exactly, beyond it through the far field.  Default: the
        model's 99 % energy radius, or less where the pairs would exceed ``max_pairs``.
    max_pairs : float
        The most vertex pairs the near field may hold (its memory: 240–330 bytes a pair).
    angles : bool
        Lean the near transport toward the light's direction where the model has a lean
        (:mod:`translucency.model.lean`).

    Examples
    --------
    >>> from translucency import TransportOptions
    >>> TransportOptions().kind, TransportOptions.of(paper=True).kind
    ('default', 'paper')
    >>> TransportOptions(radius=-1.0)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: radius: must be >= 1e-06, got -1.0
    """

    kind: str = "default"
    radius: float | None = None
    max_pairs: float = MAX_PAIRS
    angles: bool = False

    def __post_init__(self):
        transport_kind(self.kind)  # a name not registered: one line naming the known ones
        check_option("radius", self.radius, lo=1e-6, hi=1e9)  # 1 nm to 1000 km (the far field divides by r²)
        check_option("max_pairs", self.max_pairs, lo=1)

    @classmethod
    def of(
        cls,
        options: TransportOptions | str | None = None,
        *,
        paper: bool = False,
        angles: bool = False,
        radius: float | None = None,
        max_pairs: float | None = None,
    ) -> TransportOptions:
        """``options`` (default: the defaults; a kind's name: the defaults with that kind) with the user's
        flags laid over it: ``paper`` draws the ``paper`` kind, ``angles`` the lean, ``radius`` and
        ``max_pairs`` as given (None: as they were)."""
        base = cls() if options is None else cls(kind=options) if isinstance(options, str) else options
        if not isinstance(base, cls):
            raise TranslucencyError(f"transport: expected TransportOptions, got {type(base).__name__}")
        changes = {}
        if paper:
            if base.kind not in ("default", "paper"):
                raise TranslucencyError(
                    f"--paper draws the paper's model; --transport {base.kind}: choose one"
                )
            changes["kind"] = "paper"
        if angles:
            changes["angles"] = True
        if radius is not None:
            changes["radius"] = radius
        if max_pairs is not None:
            changes["max_pairs"] = max_pairs
        return dataclasses.replace(base, **changes) if changes else base

    def record(self) -> dict:
        """The choices as a summary states them."""
        return dataclasses.asdict(self)
