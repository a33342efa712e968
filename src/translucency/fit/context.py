"""What every chunk of a fit shares: the source, the model family and the fit's options (checked before, in
:mod:`.options`).  It imports nothing of the fit: the families, the chunks and the rounds all name it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["FitContext"]


@dataclass(kw_only=True)
class FitContext:
    """What every chunk of a fit shares: the source, the model family and the fit options.

    Examples
    --------
    >>> from translucency.fit.families import FAMILIES
    >>> ctx = FitContext(source=None, family=FAMILIES["aniso"], n=3, m=8, C=3, exclusion=0.25, rel_sigma=0.05,
    ...                  eta=1.3, radius_step=None, sweeps=2, balance=True, x_i=np.zeros((4, 2)),
    ...                  weighting="relative")
    >>> ctx.kind, ctx.family.directional, ctx.rho   # ρ = rel_sigma under "relative" weighting
    ('aniso', True, 0.05)
    >>> FitContext(source=None, family=FAMILIES["iso"], n=3, m=1, C=3, exclusion=0.25, rel_sigma=0.05,
    ...            eta=1.3, radius_step=None, sweeps=1, balance=True, x_i=np.zeros((4, 2))).rho  # "poisson"
    0.0
    """

    source: object  # where the chunks come from: a planar or a mesh source
    family: object  # the model family (a :class:`~translucency.fit.families.Family` of ``FAMILIES``)
    n: int  # exponential terms per profile
    m: int  # directions (1 unless anisotropic)
    C: int  # colour rows: 1 (shared colour scale) or 3
    exclusion: float  # pixels closer than this to x_i are left out, mm
    rel_sigma: float  # ρ, the relative tolerance in the weights ("relative" weighting)
    eta: float  # refractive index (dipole)
    radius_step: float | None  # width of the merged rings beyond 1 mm, mm; None: exact radii only
    sweeps: int  # block-coordinate sweeps over the directions per round
    balance: bool  # weight rings beyond 1 mm by 1 mm / r
    x_i: np.ndarray  # (P, 2|3) incident points, mm
    rate_bounds: tuple | None = None  # (lo, hi) of log a (a in mm⁻¹); None: what the radii resolve
    g: float = 0.0  # the medium's mean cosine (PBD's single scattering), from the data set's header
    cache_left: float = 0.0  # bytes the data may still occupy in memory between rounds
    cache: dict = field(default_factory=dict)
    weighting: str = "poisson"  # one of WEIGHTINGS (module docstring)

    @property
    def kind(self) -> str:
        """The family's name (one of :data:`~translucency.fit.options.KINDS`)."""
        return self.family.name

    @property
    def rho(self) -> float:
        """ρ of the weights: ``rel_sigma`` for the "relative" weighting, 0 for "poisson"."""
        return float(self.rel_sigma) if self.weighting == "relative" else 0.0
