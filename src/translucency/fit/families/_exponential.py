"""The sums of exponentials (the paper's eq. (1)): what the isotropic and the anisotropic family share.

P_i(r) = Σ_k c_k e^{−a_k r} per colour row (and direction), fitted by variable
projection (:mod:`translucency.solvers.varpro`): every (point, colour row[,
direction]) sub-problem at once, warm from the previous round where the point
is ready, else from starts pooled over fixed blocks of
:data:`~translucency.fit.chunk.POOL_POINTS` points.  With the shared colour
(C = 1) the scale (1, s_g, s_b) of each point is solved in closed form after the
fall-offs.
"""

from __future__ import annotations

from abc import abstractmethod
from typing import TYPE_CHECKING

import numpy as np

from ...model import ExponentialModel
from ...solvers import fit_exponentials_batched, rate_bounds
from .._pixels import predict
from ..chunk import POOL_POINTS
from ._base import AUTO_DIRECTIONS, AUTO_TERMS, Family

if TYPE_CHECKING:  # annotations only
    from ..chunk import Chunk
    from ..context import FitContext
    from ..state import FitState


def exp_sum(c, a, r):
    """Σ_k c_k e^{−a_k r}: c, a (..., n) broadcast against r (...) in mm."""
    return np.einsum("...k,...k->...", c, np.exp(-a * r[..., None]))


def fit_cold(ctx: FitContext, ch: Chunk, W, Y, point: np.ndarray, radii=None, **options):
    """``fit_exponentials_batched`` from pooled starts, pooled over fixed blocks of :data:`POOL_POINTS`
    points (``point``: each row's point within the chunk); returns c, a of shape (rows, n)."""
    r_g, r_base = (ch.r_g, ch.r_base) if radii is None else radii
    block = (ch.first + np.asarray(point)) // POOL_POINTS
    c, a = np.zeros((len(W), ctx.n)), np.ones((len(W), ctx.n))
    for b in np.unique(block):
        sel = block == b
        c[sel], a[sel], _ = fit_exponentials_batched(
            r_g,
            W[sel],
            Y[sel],
            ctx.n,
            r_base=r_base,
            n_starts=3,
            pooled=True,
            bounds=ctx.rate_bounds or rate_bounds(ch.r_g),
            **options,
        )
    return c, a


def solve_exponentials(ctx, state, sl, ch, W, Y, index, radii=None):
    """Fit the sub-problems at ``index`` (into c/a viewed as (k·C·m, n)); warm where ready.

    ``radii``: (r, base) of the columns of W and Y when they are not the chunk's groups."""
    r_g, r_base = (ch.r_g, ch.r_base) if radii is None else radii
    c = state.c[sl].reshape(-1, ctx.n)
    a = state.a[sl].reshape(-1, ctx.n)
    ready = np.repeat(state.ready[sl], state.c.shape[1] * state.c.shape[2])[index]
    per_point = state.c.shape[1] * state.c.shape[2]  # rows (colour row, direction) of one point
    for warm in (True, False):
        sel = ready if warm else ~ready
        if not sel.any():
            continue
        rows = index[sel]
        if warm:
            cc, aa, _ = fit_exponentials_batched(
                r_g,
                W[sel],
                Y[sel],
                ctx.n,
                rates0=a[rows],
                r_base=r_base,
                n_starts=3,
                max_iter=15,
                tol=1e-4,
                bounds=ctx.rate_bounds or rate_bounds(ch.r_g),
            )
        else:
            cc, aa = fit_cold(ctx, ch, W[sel], Y[sel], rows // per_point, max_iter=12, tol=1e-4, radii=radii)
        c[rows], a[rows] = cc, aa
    state.c[sl] = c.reshape(state.c[sl].shape)
    state.a[sl] = a.reshape(state.a[sl].shape)


def _fit_colour(ctx: FitContext, state: FitState, sl: slice, ch: Chunk, w2) -> None:
    """Closed-form s_λ = Σ w² α P y / Σ w² (α P)², then (1, s_g, s_b) with the red scale moved into c."""
    state.s[sl] = 1.0
    f = ch.alpha * predict(ctx, state, sl, ch)  # s = 1 here
    num = np.einsum("kjc,kjc->kc", w2 * f, ch.y)
    den = np.einsum("kjc,kjc->kc", w2 * f, f)
    s = np.divide(num, den, out=np.ones_like(num), where=den > 0)
    red = np.where(s[:, :1] > 0, s[:, :1], 1.0)
    state.s[sl] = s / red
    state.c[sl] *= red[:, :, None, None]


class ExponentialFamily(Family):
    """Σ_k c_k e^{−a_k r} per point, colour row and direction (c in mm⁻², a in mm⁻¹), α of mean 1."""

    shared_colour = True

    def params_per_point(self, n_terms, n_directions, colour: str) -> int:
        m = (max(AUTO_DIRECTIONS) if n_directions == "auto" else n_directions) if self.directional else 1
        n = max(AUTO_TERMS) if n_terms == "auto" else n_terms
        return (1 if colour == "shared" else 3) * m * n * 2 + 2

    def profiles(self, ctx, params, sl, r_g):
        return exp_sum(params.c[sl][:, None], params.a[sl][:, None], r_g[None, :, None, None])

    def fit(self, ctx, state, sl, ch, w2):
        self.fit_profiles(ctx, state, sl, ch, w2)
        if ctx.C == 1:
            _fit_colour(ctx, state, sl, ch, w2)

    @abstractmethod
    def fit_profiles(self, ctx: FitContext, state: FitState, sl: slice, ch: Chunk, w2) -> None:
        """The fall-offs (colour scale fixed), every (point, colour row[, direction]) by VarPro."""

    def rescale(self, state, mean):
        state.c[...] *= mean

    def keep_totals(self, model, bound):
        total = model.total_reflectance()  # (N, 3): the blend's total for m directions
        over = total > bound
        points = np.flatnonzero(over.any(axis=1))
        if points.size:
            ratio = np.where(over, bound / np.where(over, total, 1.0), 1.0)[points]
            # the shared colour's one fall-off (C = 1) scales all three channels alike: by the smallest
            factor = ratio.min(axis=1, keepdims=True) if model.c.shape[1] == 1 else ratio
            model.c[points] *= factor[:, :, None, None]
        return points

    def build(self, ctx, state, alpha, frame):
        d = -state.a
        if ctx.C == 1:
            return ExponentialModel(
                ctx.x_i, state.c, d, alpha, s_g=state.s[:, 1], s_b=state.s[:, 2], frame=frame
            )
        return ExponentialModel(ctx.x_i, state.c, d, alpha, frame=frame)
