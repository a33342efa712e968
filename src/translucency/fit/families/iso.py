"""The isotropic family ``iso``: the paper's Σ_k c_k e^{d_k r} per point (and colour row)."""

from __future__ import annotations

import numpy as np

from .._pixels import grouped
from .._regularise import bound_totals
from ._exponential import ExponentialFamily, solve_exponentials


class IsoFamily(ExponentialFamily):
    """One radial sum of exponentials per point and colour row; its total bounded (energy guard)."""

    name = "iso"
    time_terms = {"overhead": 0.3, "point_pixels": 1.0e-6}

    def fit_profiles(self, ctx, state, sl, ch, w2):
        k, C, G = ch.y.shape[0], ctx.C, ch.r_g.size
        kappa = ch.alpha * state.s[sl][:, None, :].astype(np.float32) if C == 1 else ch.alpha  # (k, J, 3)
        W, Y = grouped(ch.rings, G, C, w2, kappa, ch.y)
        solve_exponentials(ctx, state, sl, ch, W, Y, np.arange(k * C))
        c, a = bound_totals(ctx, ch, state.c[sl].reshape(-1, ctx.n), state.a[sl].reshape(-1, ctx.n), W, Y)
        state.c[sl], state.a[sl] = c.reshape(state.c[sl].shape), a.reshape(state.a[sl].shape)
