"""One round's work on a chunk of incident points, block by block (:data:`~.chunk.FIT_BLOCK`).

A block's work: read (or take from the cache) its data, weight it (round 1 by
ring means of the data, later rounds by the reference model), let the family fit
its parameters with α fixed, then Φ and the α statistics Σ w²Py, Σ w²P² with
the new parameters (as boxes of the α grid).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ._pixels import pixel_sums, predict
from .chunk import FIT_BLOCK, load_chunk, objective, weights
from .state import FitState

if TYPE_CHECKING:  # annotations only
    from .context import FitContext


def _blocks(s: int, e: int) -> list[tuple[int, int]]:
    """Points s..e cut at the multiples of :data:`FIT_BLOCK`."""
    cuts = range((s // FIT_BLOCK + 1) * FIT_BLOCK, e, FIT_BLOCK)
    edges = [s, *cuts, e]
    return list(zip(edges[:-1], edges[1:]))


def _rows(raw: tuple, i0: int, i1: int, k: int) -> tuple:
    """Rows i0..i1 of what a source read for k points (arrays with one row for all stay whole)."""
    return tuple(
        x[i0:i1] if isinstance(x, np.ndarray) and x.ndim and x.shape[0] == k and k > 1 else x for x in raw
    )


def _merge_boxes(parts: list) -> tuple:
    """One (box, values) of several :func:`compact` boxes, summed in list order."""
    full = [p for p in parts if p[1].size]
    if not full:
        return parts[0]
    nd = len(full[0][0])
    box = tuple(slice(min(p[0][d].start for p in full), max(p[0][d].stop for p in full)) for d in range(nd))
    out = np.zeros(tuple(b.stop - b.start for b in box), dtype=full[0][1].dtype)
    for b, v in full:
        out[tuple(slice(b[d].start - box[d].start, b[d].stop - box[d].start) for d in range(nd))] += v
    return box, out


def fit_chunk(ctx: FitContext, glob: FitState, s: int, e: int):
    """One round's work on points s..e (block by block, :data:`FIT_BLOCK`): parameters, colour scale,
    α statistics, Φ.

    Returns the points' new state, their Φ (new parameters, the round's α) and, in round 2, Φ of
    the reference state, and Σ w²Py and Σ w²P² (per sample pixel, as a box).
    """
    blocks = _blocks(s, e)
    if len(blocks) == 1:
        return _fit_block(ctx, glob, s, e)
    # blocks that are whole chunks of the store are read one by one (the chunk's data is never in
    # memory at once); otherwise one read for the whole chunk (no stored chunk decoded twice)
    stored = getattr(ctx.source, "stored_points", 0)
    aligned = stored > 0 and FIT_BLOCK % stored == 0 and all(b0 % stored == 0 for b0, _ in blocks)
    raw = None if aligned or all(b in ctx.cache for b in blocks) else ctx.source.read(ctx, s, e)
    results = []
    for b0, b1 in blocks:
        part = None if raw is None or (b0, b1) in ctx.cache else _rows(raw, b0 - s, b1 - s, e - s)
        results.append(_fit_block(ctx, glob, b0, b1, part))
    del raw
    state = FitState.of_points(
        {key: np.concatenate([getattr(r[0], key) for r in results]) for key in FitState.PER_POINT}, glob.alpha
    )
    phi = sum((r[1] for r in results), 0.0)
    phi_ref = sum((r[2] for r in results), 0.0)
    return state, phi, phi_ref, _merge_boxes([r[3] for r in results]), _merge_boxes([r[4] for r in results])


def _fit_block(ctx: FitContext, glob: FitState, s: int, e: int, raw=None):
    """:func:`fit_chunk` for the points of one block (``raw``: their data, if already read)."""
    state = glob.points(s, e)
    ch = load_chunk(ctx, state, s, e, raw)
    k = e - s
    sl = slice(0, k)
    usable = ch.usable
    state.flagged[sl] = ~usable
    if k and not state.ready[sl].all() and ctx.C == 1:  # colour scale from the window sums
        tot = ch.y.sum(axis=1, dtype=np.float64)
        state.s[sl] = np.where(
            state.ready[sl, None],
            state.s[sl],
            tot / np.maximum(tot[:, :1], 1e-300) * (tot[:, :1] > 0) + (tot[:, :1] <= 0),
        )
    # the weights: round 1 from ring means of the data, every later round from the reference model
    # (round 1's result), so that all rounds after the first minimise, and are scored by, one Φ
    phi_ref = 0.0
    if glob.round[0] == 0:
        w2 = weights(ctx, ch, None)
    else:
        ref = glob.reference(s, e)
        ref_model = predict(ctx, ref, sl, ch)
        ref_model *= ch.per_channel(ref.alpha.astype(np.float32).ravel()[ch.pixel])
        w2 = weights(ctx, ch, ref_model.copy())
        if glob.round[0] == 1:  # round 2 starts from the reference: its Φ under its own weights
            phi_ref = objective(w2 * usable[:, None, None], ref_model, ch.y)
        del ref_model
    ctx.family.fit(ctx, state, sl, ch, w2)
    # inert parameters where a point has no data
    ctx.family.make_inert(state, np.flatnonzero(~usable))
    state.ready[sl] = True
    # Φ and the α statistics (summed over channels, then per sample pixel) with the new parameters
    f = predict(ctx, state, sl, ch)
    w2 *= usable[:, None, None]
    phi = objective(w2, ch.alpha * f, ch.y)
    wf = w2 * f
    pixel, ones, shape = ch.pixel.ravel(), np.ones(3, np.float32), glob.alpha.shape
    num = pixel_sums(pixel, ((wf * ch.y) @ ones).ravel(), shape)
    den = pixel_sums(pixel, ((wf * f) @ ones).ravel(), shape)
    return state, phi, phi_ref, num, den
