"""A chunk's profiles at its pixels and the sums over its rings and α samples.

The group profiles F (k, G, C, m) of a family are gathered at each pixel's
radius group (blended between directions by the hat weights of θ); the fits
reduce weighted products over each (point, radius group), and α's statistics
over each α sample.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..cluster import compact
from ._windows import Segments

if TYPE_CHECKING:  # annotations only
    from .chunk import Chunk
    from .context import FitContext
    from .state import FitState, Params


def hat(theta, m):
    """Lower direction l0 and the fraction t towards l0 + 1 of each angle (hat weights).

    This is the (l0, t) form of :func:`translucency.model.directions.direction_weights`:
    direction l0 has weight 1 − t and direction (l0 + 1) mod m weight t.
    """
    u = np.mod(theta / (2 * np.pi / m), m)
    l0 = np.floor(u)
    return l0.astype(np.int64) % m, (u - l0).astype(np.float32)


def at_pixels(F: np.ndarray, ch: Chunk, m: int, direction=None) -> np.ndarray:
    """Gather group profiles F (k, G, C, m) at the pixels: blended by the hat weights,
    or of one ``direction`` (1|k, J) per pixel; returns (k, J, C)."""
    if m == 1 and direction is None:
        return ch.rings.spread(F[..., 0])
    k, G, C, _ = F.shape
    rows = F.transpose(0, 1, 3, 2).reshape(k, G * m, C)  # row g·m + l: group g, direction l

    def at(l):  # the profile of direction l (1|k, J) at each pixel's radius group
        idx = ch.gid * m + l
        if idx.shape[0] == 1:
            return np.take(rows, idx[0], axis=1)
        return np.take_along_axis(rows, idx[..., None], axis=1)

    if direction is not None:
        return at(direction)
    l0, t = hat(ch.theta, m)
    t = np.repeat(t[..., None], C, axis=2)  # (1|k, J, C): like-shaped operands are fast
    f = at(l0)
    f *= 1 - t
    f1 = at((l0 + 1) % m)
    f1 *= t
    f += f1
    return f


def predict(ctx: FitContext, state: FitState | Params, sl: slice, ch: Chunk) -> np.ndarray:
    """Current P_i at every pixel of the chunk, (k, J, 3), without α."""
    # float32 at the pixels: these arrays only weight, accumulate and report
    f = at_pixels(ctx.family.profiles(ctx, state, sl, ch.r_g).astype(np.float32), ch, ctx.m)
    return f * state.s[sl][:, None, :].astype(np.float32) if ctx.C == 1 else f


def pixel_sums(pixel: np.ndarray, values: np.ndarray, shape) -> tuple:
    """Σ ``values`` per α sample (flat indices ``pixel`` into ``shape``) as the smallest box holding every
    non-zero sum (:func:`translucency.cluster.compact`): a chunk's statistics cover its windows, not the
    grid.  The same sums as a ``bincount`` over the whole grid, bit for bit (each sample's values are
    added in the same order)."""
    if not pixel.size:
        return compact(np.zeros((0,) * len(shape)))
    row = int(np.prod(shape[1:], dtype=np.int64))  # samples per row of the first axis
    r0, r1 = int(pixel.min()) // row, int(pixel.max()) // row + 1  # the rows the pixels lie in
    band = np.bincount(pixel - r0 * row, values, (r1 - r0) * row).reshape((r1 - r0, *shape[1:]))
    box, inner = compact(band)
    return (slice(box[0].start + r0, box[0].stop + r0), *box[1:]), inner


def grouped(seg: Segments, G: int, C: int, w2, kappa, target, overwrite: bool = False):
    r"""Sums :math:`A = \sum w^2\kappa^2` and :math:`B = \sum w^2 \kappa y` over each
    (point, key) of ``seg`` (keys: sub-problem · G + radius group), channels summed
    when C = 1; returns W = √A and Y = B/A as rows (point, colour row, sub-problem), (·, G).

    ``overwrite``: kappa and target are scratch and may hold the integrands (saves memory).
    """
    wk = w2 * kappa
    if overwrite:
        a_int, b_int = np.multiply(kappa, wk, out=kappa), np.multiply(target, wk, out=target)
    else:
        a_int, b_int = wk * kappa, wk * target
    del wk
    A, B = seg.sums(a_int), seg.sums(b_int)  # (k, n_sub·G, 3)
    if C == 1:
        A, B = A.sum(axis=2, keepdims=True), B.sum(axis=2, keepdims=True)
    k = A.shape[0]
    A, B = (x.reshape(k, -1, G, C).transpose(0, 3, 1, 2).reshape(-1, G).astype(np.float64) for x in (A, B))
    return np.sqrt(A), np.divide(B, A, out=np.zeros_like(B), where=A > 0)
