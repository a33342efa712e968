"""The protocol every model family of the fit follows (:class:`Family`).

A family is one object (:data:`translucency.fit.families.FAMILIES`) that knows
its parameters, its profile P_i(r) at the rings of a chunk, its fit step with α
fixed, what becomes of its amplitudes when α is normalised to mean 1, the model
it builds from the fit's state, and the rates of its time estimate.  The
alternation (:mod:`translucency.fit._rounds`) and the chunk's work
(:mod:`translucency.fit._block`) ask the family and never switch on its name.

The protocol names only public types of the fit: :class:`~translucency.fit.options.FitContext` (what
every chunk shares), :class:`~translucency.fit.state.FitState` and :class:`~translucency.fit.state.Params`
(the parameters), :class:`~translucency.fit.chunk.Chunk` (a chunk's data), so that a family written
outside the package is typed against what it may import.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, ClassVar

import numpy as np

if TYPE_CHECKING:  # annotations only (fit.options imports this package, for FAMILIES)
    from ...model import ReflectanceModel
    from ..chunk import Chunk
    from ..context import FitContext
    from ..state import FitState, Params

#: the candidates of model selection (``n_terms="auto"``, ``n_directions="auto"``)
AUTO_TERMS = (1, 2, 3, 4)
AUTO_DIRECTIONS = (1, 2, 4, 8, 16)


class Family(ABC):
    """One model family of the fit: P_i(r) per incident point, fitted with α fixed.

    Attributes
    ----------
    name : str
        The family's name (``fit --model NAME``; ``FitContext.kind``).
    summary : str
        What ``fit --model``'s help says of it after its name, in parentheses (empty: the name says
        it; :func:`~translucency.fit.families.describe_families`).
    shared_colour : bool
        ``colour="shared"`` applies: one fall-off scaled by (1, s_g, s_b) (C = 1 colour row).
    directional : bool
        The family has m > 1 directions (``n_directions``; m ≥ 2 required).
    keeps_alpha_scale : bool
        No free amplitude (σ_a, σ_s'): α is not normalised to mean 1, it keeps the scale.
    time_terms : dict
        Seconds of ``translucency fit`` on the development machine: ``overhead`` and per
        ``point_pixels`` (points × window pixels, or vertices, × rounds).

    Examples
    --------
    The isotropic family's profile is Σ_k c_k e^{−a_k r}: one term c = 1 mm⁻², a = 2 mm⁻¹ gives
    e^{−2r}; normalising α to mean 1/2 moves the factor into c (αP unchanged):

    >>> import numpy as np
    >>> from translucency.fit.families import FAMILIES
    >>> from translucency.fit.state import FitState
    >>> iso = FAMILIES["iso"]
    >>> iso, iso.shared_colour, iso.keeps_alpha_scale, FAMILIES["dipole"].keeps_alpha_scale
    (<IsoFamily 'iso'>, True, False, True)
    >>> iso.params_per_point(2, 1, "per-channel"), iso.params_per_point(2, 1, "shared")
    (14, 6)
    >>> st = FitState(P=1, C=1, m=1, n=1, alpha_shape=(2, 2))
    >>> st.c[...], st.a[...] = 1.0, 2.0
    >>> iso.profiles(None, st, slice(0, 1), np.array([0.0, 0.5, 1.0])).ravel().round(4)
    array([1.    , 0.3679, 0.1353])
    >>> iso.rescale(st, 0.5)
    >>> st.c.ravel().tolist()
    [0.5]
    """

    name: ClassVar[str]
    summary: ClassVar[str] = ""
    shared_colour: ClassVar[bool] = False
    directional: ClassVar[bool] = False
    keeps_alpha_scale: ClassVar[bool] = False
    time_terms: ClassVar[dict]

    @abstractmethod
    def params_per_point(self, n_terms, n_directions, colour: str) -> int:
        """Stored parameters per incident point (``"auto"`` counts the largest candidate)."""

    @abstractmethod
    def profiles(self, ctx: FitContext, params: Params | FitState, sl: slice, r_g: np.ndarray) -> np.ndarray:
        """Each point's profile at the group radii r_g (mm), (k, G, C, m), without α or colour scale."""

    @abstractmethod
    def fit(self, ctx: FitContext, state: FitState, sl: slice, ch: Chunk, w2: np.ndarray) -> None:
        """One round's fit of points ``sl`` of the chunk ``ch`` with α fixed, weights ``w2`` (k, J, 3)."""

    def make_inert(self, state: FitState, bad: np.ndarray) -> None:
        """Parameters of zero reflectance at the points ``bad`` (no usable data)."""
        state.c[bad] = 0.0
        state.a[bad] = 1.0

    @abstractmethod
    def rescale(self, state: FitState, mean: float) -> None:
        """Take the scale ``mean`` from α (normalised to mean 1) into the amplitudes: αP unchanged."""

    @abstractmethod
    def build(self, ctx: FitContext, state: FitState, alpha, frame) -> ReflectanceModel:
        """The fitted reflectance model of the current state, with the source's α and frames."""

    def keep_totals(self, model: ReflectanceModel, bound: np.ndarray) -> np.ndarray:
        """Scale down, in place, the amplitudes of the points of ``model`` whose total reflectance exceeds
        ``bound`` (N, 3) in some channel, to the bound; returns those points' indices.

        The fit's energy guard bounds each round's profiles, but α's normalisation to mean 1 moves its
        scale into the amplitudes afterwards (:meth:`rescale`), and with few windows over a pixel that
        factor is far from 1; this keeps the returned model within the bound.  Default: nothing to
        scale (the physical baselines' totals follow from σ_a, σ_s' and are below 1 by construction).
        """
        return np.zeros(0, dtype=np.int64)

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}>"
