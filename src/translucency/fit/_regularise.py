r"""The anisotropic regularisation (James–Stein shrinkage and anchors) and the energy guard.

*Anisotropic regularisation.*  A direction sees about 2/m of a window, so its
ring means are √(m/2) times noisier than the isotropic ones, and 6 free
parameters per direction and channel follow that noise (in-sample below the
noise floor, held-out worse than the isotropic model on homogeneous
material).  Two things keep the directions honest (:func:`regularise`):

* *shrinkage* — direction l's ring means :math:`Y_{lg}` are pulled towards the
  inverse-variance mean :math:`\bar Y_g` of the directions fitted with it,
  :math:`Y'_{lg} = \bar Y_g + b_l (Y_{lg} - \bar Y_g)`, by the empirical-Bayes
  (James–Stein) factor :math:`b_l = S_l / (S_l + q)`, where
  :math:`S_l = \max(\chi^2_l - E_l - 2\sqrt{2 E_l}, 0)` is the directional
  signal beyond the noise (:math:`\chi^2_l = \sum_g \sigma_{lg}^{-2} (Y_{lg} - \bar Y_g)^2`,
  :math:`E_l` its expectation under noise alone, :data:`SIGNIFICANCE` = 2 of its
  standard deviations discounted) and q = 2n the parameters a direction's
  profile can give the noise.  A homogeneous material gets b ≈ 0 (every
  direction the isotropic profile), a fibrous one b ≈ 1.
* *anchors* — inside the first ring and beyond the window the data say nothing
  about direction (and at r = 0 R_d has one value whatever the direction); each
  direction's profile is tied to the point's isotropic fit at r = 0 (weighted
  like its rings within 1.5 × its first radius) and at 1.5, 2 and 3 × the
  window's largest radius (like its outer fifth), so that no direction grows a
  spike at x_i or a slow tail whose integral outside the observed annulus
  inflates the total reflectance.

Both act on noisy windows only (a photon count or a variance); noise-free data
are fitted as they are.

*Energy guard.*  An isotropic profile whose total reflectance
:math:`2\pi\sum_k c_k/a_k^2` exceeds what the point can reflect (1, or a photon
tally's measured total + 20 %) is refitted with narrower rates
(:func:`bound_totals`): its excess lies where the window does not look, beyond
its edge or inside its first pixel.  The anisotropic directions, fitted from
that bounded profile, are held to the same bound by their blend's total
(:func:`bound_directions`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..solvers import fit_exponentials_batched, rate_bounds
from .chunk import distance_balance

if TYPE_CHECKING:  # annotations only
    from .chunk import Chunk
    from .context import FitContext
    from .state import FitState


#: where each direction is tied to the isotropic fit: at the head, in units of the smallest radius
#: fitted (r → 0, where R_d has one value whatever the direction, and half-way to the first ring),
#: and at the tail, in units of the window's largest radius
HEAD_ANCHORS = np.array([0.0])
HEAD_RINGS = 1.5  # the head anchor weighs like a direction's rings within 1.5 × its first radius
#: directional signal counts only beyond this many standard deviations √(2E) of χ² under noise alone
SIGNIFICANCE = 2.0
TAIL_ANCHORS = np.array([1.5, 2.0, 3.0])


def anchor_radii(r_g: np.ndarray) -> np.ndarray:
    """The anchors' radii (mm) for a chunk's ring radii ``r_g``."""
    return np.r_[HEAD_ANCHORS * r_g[r_g > 0].min(), TAIL_ANCHORS * r_g.max()]


def regularise(ctx: FitContext, state: FitState, sl: slice, ch: Chunk, W, Y, n_cls: int):
    """Shrink one class of direction sub-problems towards their mean and anchor their heads and
    tails (module docstring): W, Y (k·C·n_cls, G) → (·, G + anchors)."""
    G = ch.r_g.size
    k, C = W.shape[0] // (ctx.C * n_cls), ctx.C
    W4, Y4 = W.reshape(k, C, n_cls, G), Y.reshape(k, C, n_cls, G)
    # σ⁻² of each ring mean: W² without the distance balance (W² = b(r) / σ²)
    ivar = W4**2 / distance_balance(ctx, ch.r_g)
    # Ȳ: the inverse-variance mean over the class's directions, per point, colour row and ring
    tot = ivar.sum(axis=2, keepdims=True)
    Y_bar = np.divide((ivar * Y4).sum(axis=2, keepdims=True), tot, out=np.zeros_like(tot), where=tot > 0)
    # χ² of each direction about Ȳ and its expectation under noise alone, Σ_g (1 − σ⁻²_l / Σ_l σ⁻²)
    chi2 = (ivar * (Y4 - Y_bar) ** 2).sum(axis=3)
    expected = np.divide(ivar, tot, out=np.ones_like(ivar), where=tot > 0)
    expected = ((1.0 - expected) * (W4 > 0)).sum(axis=3)
    S = np.maximum(chi2 - expected - SIGNIFICANCE * np.sqrt(2.0 * expected), 0.0)
    b = S / (S + 2.0 * ctx.n)  # the James–Stein factor b_l ∈ [0, 1)
    # noise-free windows (no variance: a simulation's exact profiles) have no noise to shrink or anchor
    noisy = ch.noisy[:, None, None]
    b = np.where(noisy, b, 1.0)
    Y_shrunk = Y_bar + b[..., None] * (Y4 - Y_bar)
    # anchors: the isotropic fit at the head and tail radii, weighted like the inner and the outer
    # fifth of the window's rings together (the rings a spike or a slow term would be fitted to)
    r_h, r_t = HEAD_ANCHORS * ch.r_g[ch.r_g > 0].min(), TAIL_ANCHORS * ch.r_g.max()
    c0, a0 = state.c_iso[sl], state.a_iso[sl]  # (k, C, n)
    F = np.einsum("kcn,kcnt->kct", c0, np.exp(-a0[..., None] * np.r_[r_h, r_t]))[:, :, None, :]
    span = ch.r_g.max() - ch.r_g.min()
    # the head: the rings within HEAD_RINGS × each direction's own first radius (with m = 16 some
    # directions see no pixel at the window's smallest radius)
    r_first = np.where(W4 > 0, ch.r_g, np.inf).min(axis=3, keepdims=True)
    W2_inner = (W4**2 * (ch.r_g <= HEAD_RINGS * r_first)).sum(axis=3)
    W2_outer = (W4[..., ch.r_g >= ch.r_g.max() - 0.2 * span] ** 2).sum(axis=3)
    W_a = np.sqrt(
        np.concatenate(
            [
                np.repeat(W2_inner[..., None], r_h.size, axis=3),
                np.repeat(W2_outer[..., None], r_t.size, axis=3),
            ],
            axis=3,
        )
    )
    W_a = W_a * noisy[..., None]
    W_out = np.concatenate([W4, W_a], axis=3).reshape(-1, G + W_a.shape[3])
    Y_out = np.concatenate([Y_shrunk, np.broadcast_to(F, W_a.shape)], axis=3).reshape(-1, G + W_a.shape[3])
    return W_out, Y_out


#: factors by which the slowest admissible rate is raised, in turn, for a profile whose total is too large
TAIL_STEPS = (1.5, 2.0, 3.0, 4.0, 6.0, 8.0)


def row_bounds(ctx: FitContext, ch: Chunk) -> np.ndarray:
    """(k, C) the most total reflectance of each point's colour rows (``ch.total_bound``: per channel for
    C = 3; red for the shared colour's one row, C = 1)."""
    return ch.total_bound if ctx.C == 3 else ch.total_bound[:, :1]


def bound_totals(ctx: FitContext, ch: Chunk, c, a, W, Y):
    r"""Refit, narrower, the isotropic profiles (rows of c, a: (k·C, n); W, Y their grouped data) whose
    total :math:`2\pi \sum_k c_k / a_k^2` exceeds the source's bound (``total_bound``: 1, and a tally's
    measured total + 20 %); returns c, a.

    A window of radius R cannot tell a term of rate a ≲ 1/R from a constant, nor see inside its first
    pixel: fitted, such a term carries little of the window's energy and, integrated, up to several
    times the point's real total (docs/fitting.md).  For those profiles alone the admissible rates are
    narrowed by :data:`TAIL_STEPS` (the slowest raised, the fastest lowered alike), a refit kept where it
    lowers the total, until the total is within the bound; every other profile, and every noise-free one,
    is untouched.  The anisotropic directions are not bounded themselves: they are tied to this bounded
    isotropic fit (:func:`regularise`).
    """
    if ch.total_bound is None:
        return c, a
    c, a = c.copy(), a.copy()
    bound_row = row_bounds(ctx, ch).reshape(-1)
    noisy_row = np.repeat(ch.noisy, ctx.C)  # noise-free profiles determine their own tails

    def total(rows):
        return 2 * np.pi * np.sum(c[rows] / a[rows] ** 2, axis=1)

    bad = np.flatnonzero((total(np.arange(len(c))) > bound_row) & noisy_row)
    lo, hi = ctx.rate_bounds or rate_bounds(ch.r_g)
    for factor in TAIL_STEPS:
        if not bad.size:
            break
        floor, ceiling = lo + np.log(factor), hi - np.log(factor)
        cc, aa, _ = fit_exponentials_batched(
            ch.r_g,
            W[bad],
            Y[bad],
            ctx.n,
            rates0=np.clip(a[bad], np.exp(floor), np.exp(ceiling)),
            r_base=ch.r_base,
            n_starts=1,
            max_iter=20,
            tol=1e-5,
            bounds=(floor, ceiling),
        )
        # a refit is kept only where it lowers the total (narrower rates can also push the steep start
        # onto slower terms, which carry more energy)
        lower = 2 * np.pi * np.sum(cc / aa**2, axis=1) < total(bad)
        c[bad[lower]], a[bad[lower]] = cc[lower], aa[lower]
        bad = bad[total(bad) > bound_row[bad]]
    return c, a


def bound_directions(ctx: FitContext, ch: Chunk, c, a):
    r"""Lower the directions of every noisy (point, colour row) whose blend's total
    :math:`(2\pi/m) \sum_l \sum_k c_{lk} / a_{lk}^2` exceeds the source's bound (the one
    :func:`bound_totals` keeps the isotropic fit to) to it; returns c (k, C, m, n).

    The anchors tie each direction's head and tail to the bounded isotropic fit, but the directions'
    own slow terms can still integrate, beyond the window, to more than the point can reflect.  The
    excess is taken from where it lies: the slowest term of every direction (terms are sorted steepest
    first) is scaled by one factor over the directions; where those terms alone cannot carry it, every
    term is scaled by a common factor.  Both keep the ratios between the directions.
    """
    if ch.total_bound is None:
        return c
    m = c.shape[2]
    energy = (2 * np.pi / m) * c / a**2  # (k, C, m, n): each term's share of the blend's total
    total = energy.sum(axis=(2, 3))
    bound = row_bounds(ctx, ch)
    over = (total > bound) & ch.noisy[:, None]  # noise-free profiles determine their own tails
    if not over.any():
        return c
    slow = energy[..., -1].sum(axis=2)  # (k, C): the slowest terms' energy
    rest = total - slow
    tail = over & (rest <= bound) & (slow > 0)  # the slow terms alone can carry the excess
    c = c.copy()
    f_tail = np.where(tail, (bound - rest) / np.where(tail, slow, 1.0), 1.0)
    c[..., -1] *= f_tail[:, :, None]
    common = over & ~tail
    f_all = np.where(common, bound / np.where(common, total, 1.0), 1.0)
    return c * f_all[:, :, None, None]
