r"""The anisotropic family ``aniso``: m hat-blended directions of sums of exponentials per point.

.. math:: P_i(r, \theta) = (1, s_g, s_b) \sum_l w_l(\theta) \sum_k c_{lk} e^{d_{lk} r}

Every direction starts from the point's isotropic fit (its total bounded,
:func:`translucency.fit._regularise.bound_totals`) and is then updated by block
coordinate descent: directions that share no pixel (even, then odd l) are
fitted together, with the neighbours' contributions held fixed, their ring
means shrunk towards the class's mean and anchored to the isotropic fit
(:func:`translucency.fit._regularise.regularise`); their blend's total is kept
within the isotropic fit's bound (:func:`translucency.fit._regularise.bound_directions`).
"""

from __future__ import annotations

import numpy as np

from .._pixels import at_pixels, grouped, hat
from .._regularise import anchor_radii, bound_directions, bound_totals, regularise
from .._windows import Segments
from ._exponential import ExponentialFamily, fit_cold, solve_exponentials


class AnisoFamily(ExponentialFamily):
    """m ≥ 2 directions per point, each a sum of exponentials, blended by hat weights in θ."""

    name = "aniso"
    summary = "the paper's; planar data sets only"
    directional = True
    time_terms = {"overhead": 0.3, "point_pixels": 3.2e-6}

    def fit_profiles(self, ctx, state, sl, ch, w2):
        k, C, m, G = ch.y.shape[0], ctx.C, ctx.m, ch.r_g.size
        kappa = ch.alpha * state.s[sl][:, None, :].astype(np.float32) if C == 1 else ch.alpha  # (k, J, 3)
        if not state.ready[sl].all():  # start every direction from the isotropic fit
            W, Y = grouped(ch.rings, G, C, w2, kappa, ch.y)
            cc, aa = fit_cold(ctx, ch, W, Y, np.arange(k * C) // C, max_iter=25, tol=1e-5)
            cc, aa = bound_totals(ctx, ch, cc, aa, W, Y)  # the directions' anchor: a physical total
            state.c_iso[sl], state.a_iso[sl] = cc.reshape(k, C, ctx.n), aa.reshape(k, C, ctx.n)
            state.c[sl] = np.repeat(cc.reshape(k, C, 1, ctx.n), m, axis=2)
            state.a[sl] = np.repeat(aa.reshape(k, C, 1, ctx.n), m, axis=2)
            state.ready[sl] = True
        r_a = anchor_radii(ch.r_g)  # the anchors' radii (exact: their own base radii)
        radii = (np.r_[ch.r_g, r_a], np.r_[ch.r_base, r_a])
        l0, t = hat(ch.theta, m)
        l1 = (l0 + 1) % m
        classes = (
            [np.arange(0, m, 2), np.arange(1, m, 2)] if m % 2 == 0 else [np.array([l]) for l in range(m)]
        )
        for _ in range(ctx.sweeps):
            for ci, cls in enumerate(classes):
                in0, in1 = np.isin(l0, cls), np.isin(l1, cls)
                L = np.where(in0, l0, l1)  # the direction being fitted
                O = np.where(in0, l1, l0)  # its neighbour, held fixed
                u = np.where(in0, 1 - t, np.where(in1, t, 0.0)).astype(np.float32)
                f_other = at_pixels(self.profiles(ctx, state, sl, ch.r_g).astype(np.float32), ch, m, O)
                f_other = (
                    f_other * kappa if ctx.C == 1 else np.multiply(f_other, kappa, out=f_other)
                )  # (k, J, 3)
                f_other *= ch.per_channel(np.where(in0, t, 1 - t).astype(np.float32))  # the neighbour's part
                target = np.subtract(ch.y, f_other, out=f_other)
                both = in0 | in1  # (m even: every pixel borders one direction of each class)
                w_cls = w2 if both.all() else w2 * ch.per_channel(both.astype(np.float32))
                if ci not in ch.plans:  # pixels grouped by (direction, radius group), made once per chunk
                    ch.plans[ci] = Segments.of(L * G + ch.gid, k, m * G)
                W, Y = grouped(ch.plans[ci], G, C, w_cls, kappa * ch.per_channel(u), target, overwrite=True)
                del target
                rows = (np.arange(k)[:, None, None] * C + np.arange(C)[None, :, None]) * m + cls[
                    None, None, :
                ]
                rows = rows.ravel()
                W_r, Y_r = regularise(ctx, state, sl, ch, W[rows], Y[rows], len(cls))
                solve_exponentials(ctx, state, sl, ch, W_r, Y_r, rows, radii)
        # the energy guard of the blend: the directions' total within the isotropic fit's bound
        state.c[sl] = bound_directions(ctx, ch, state.c[sl], state.a[sl])
