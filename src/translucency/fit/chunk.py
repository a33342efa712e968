r"""A chunk of incident points: its data in radius-group order, and the weights of the objective.

**Objective.**  Weighted least squares over every valid pair,

.. math:: \Phi = \sum_{i,j,\lambda} w_{ij\lambda}^2
          \bigl(\alpha_j P_{i\lambda}(\vec x_j) - y_{ij\lambda}\bigr)^2, \qquad
          w^{-2} = \bigl[(\rho\, m)^2 + v_0\, m\bigr] / b(r),

with m = α P of a *reference* model (never the pixel's own noisy value), v₀ =
1/(N p²) the Poisson variance per unit reflectance for N photons per point and
pixel area p² (per vertex area on meshes; without a photon count v₀ = Σ var /
Σ y of the window, and ``"relative"`` keeps the data's ring-mean variance in
place of v₀ m), b(r) = min(1, 1 mm / r) the distance balance, and ρ by
``weighting`` (:data:`~translucency.fit.options.WEIGHTINGS`): ``"poisson"``
(default) ρ = 0, the Poisson variance of the model, whose shape does not
depend on N — more photons only shrink the noise; ``"relative"`` ρ =
``rel_sigma``, a relative error where the data are precise (its share grows
with N, so it reshapes the fit as photons grow).  Windows without any variance
(noise-free data) take the relative error.  Masked, non-finite and excluded
pixels (r below ``exclusion_mm``) have weight 0.

*Which model sets the weights.*  Round 1 has none and uses ring means of the
data (a pilot).  Its result is the reference: rounds 2, 3, … all use the
weights of that one model, so they minimise one fixed Φ and every round's
state — round 1's included — is scored by it (``history``).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from ._windows import Segments, radius_groups

if TYPE_CHECKING:  # annotations only
    from .context import FitContext
    from .state import FitState

#: incident points whose pooled profile seeds their cold starts together; blocks follow the points'
#: absolute indices, so a fit does not depend on how its points are chunked (chunks hold whole blocks)
POOL_POINTS = 16

#: points whose pixels a chunk works on at a time, on absolute multiples (as the pooled starts): the
#: chunk is read from the store at once, but its working arrays (weights, model, products: ~10 of the
#: data's size) are those of FIT_BLOCK points, so a task needs about its data, not 5× it
FIT_BLOCK = 4 * POOL_POINTS


@dataclass(kw_only=True)
class Chunk:
    """The data of k incident points, flattened to (k, J, 3), each row's pixels in radius-group order.

    Geometry is (1, J) when every window lies alike around its point (the
    usual case: points snapped to pixel centres) and (k, J) otherwise.

    Examples
    --------
    Two points sharing one geometry row of 4 pixels, the centre pixel unused; beyond 1 mm a pixel
    counts 1 mm / r:

    >>> from translucency.fit._windows import Segments, radius_groups
    >>> r = np.array([[0.0, 0.5, 1.0, 2.0]])
    >>> gid, r_g, r_base = radius_groups(r, 0.5)
    >>> ch = Chunk(y=np.ones((2, 4, 3)), valid=np.array([[False, True, True, True]] * 2),
    ...            balance=np.minimum(1.0, 1.0 / np.maximum(r, 1e-9)), var_ring=None, r=r,
    ...            theta=np.zeros_like(r), gid=gid, r_g=r_g, r_base=r_base,
    ...            rings=Segments.of(gid, 2, r_g.size), base=np.array([[0], [10]]),
    ...            local=np.arange(4)[None])
    >>> ch.static.tolist()
    [[0.0, 1.0, 1.0, 0.5], [0.0, 1.0, 1.0, 0.5]]
    >>> ch.pixel.tolist()
    [[0, 1, 2, 3], [10, 11, 12, 13]]
    >>> ch.per_channel(ch.static).shape
    (2, 4, 3)
    """

    y: np.ndarray  # (k, J, 3) data, 0 off the valid pixels
    valid: np.ndarray  # (k, J) bool: the pixel is used
    balance: np.ndarray  # (1|k, J) float32: the distance balance of each pixel's weight
    var_ring: np.ndarray | None  # (k, G, 3) ring means of the data's variance; None: Poisson model
    r: np.ndarray  # (1|k, J) mm
    theta: np.ndarray  # (1|k, J) rad, in the sample's frame
    gid: np.ndarray  # (1|k, J) radius group of each pixel
    r_g: np.ndarray  # (G,) radius of each group, mm
    r_base: np.ndarray  # (G,) ring centres (= r_g for exact radii): equally spaced for the solver
    rings: Segments  # sums over each (point, radius group)
    base: np.ndarray  # (k, 1) and ...
    local: np.ndarray  # ... (1|k, J): α's sample of each pixel is base + local
    usable: np.ndarray | None = None  # (k,) enough valid pixels and some signal
    poisson: object = 0.0  # 1/(N × pixel area): scalar, (k, 1, 1) (per window) or (k, J, 1) (vertices)
    rel2: object = 0.0  # ρ² of the weights: scalar, or (k, 1, 1) float32 per window
    alpha: np.ndarray | None = None  # (k, J, 3) float32 current α at each pixel (set per round)
    plans: dict = field(default_factory=dict)  # Segments of the anisotropic direction classes
    first: int = 0  # the chunk's first incident point (absolute index)
    noisy: np.ndarray | None = None  # (k,) bool: the window has a variance (the regularisation's noise)
    total_bound: np.ndarray | None = None  # (k, 3): the most total reflectance a point's model may have

    @property
    def static(self) -> np.ndarray:
        """(k, J) float32: valid × distance balance (0: pixel not used)."""
        return self.valid * self.balance

    @property
    def pixel(self) -> np.ndarray:
        """(k, J) flat index of each pixel's α sample."""
        return self.base + self.local

    def per_channel(self, x: np.ndarray) -> np.ndarray:
        """(k, J) → contiguous (k, J, 3): elementwise work on like-shaped arrays is several times faster."""
        return np.stack([x, x, x], axis=-1)


def ring_means(rings: Segments, valid: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Mean of v (k, J, 3) over the valid pixels of each (point, radius group): (k, G, 3)."""
    num = rings.sums(np.where(valid[..., None], v, np.float32(0.0)))
    cnt = rings.sums(valid.astype(np.float32))
    return num / np.maximum(cnt, 1.0)[..., None]


def distance_balance(ctx: FitContext, r: np.ndarray) -> np.ndarray:
    """b(r) of the weights: each mm of distance counts alike, rings beyond 1 mm weighted by 1 mm / r
    (1 everywhere without ``ctx.balance``)."""
    return np.minimum(1.0, 1.0 / np.maximum(r, 1e-9)) if ctx.balance else np.ones_like(r, dtype=np.float64)


def prepare_chunk(ctx: FitContext, s: int, e: int, raw=None) -> Chunk:
    """Read points s..e (or take them from ``raw``, what the source read for them) and put each
    window's pixels in radius-group order (done once per chunk)."""
    y, var, valid, r, theta, pixel, poisson = ctx.source.read(ctx, s, e) if raw is None else raw
    k = e - s
    pixel = np.broadcast_to(pixel, valid.shape)
    base = pixel[:, :1].astype(np.int64)
    local = (pixel - base).astype(np.int32)
    if r.shape[0] == 1:  # windows placed alike around their points: one geometry row serves all
        local = local[:1]
    gid, r_g, r_base = radius_groups(r, ctx.source.pitch, r_exact=1.0, radius_step=ctx.radius_step)
    rings = Segments.of(gid, k, r_g.size)
    valid, y, r, theta, gid, local = (rings.order(a) for a in (valid, y, r, theta, gid, local))
    if var is not None:
        var = rings.order(var)
    if np.ndim(poisson):  # per-vertex Poisson factors follow their vertices
        poisson = rings.order(np.broadcast_to(poisson, (k,) + np.shape(poisson)[1:]))
    rings = rings.in_order()
    y = np.where(valid[..., None], y, np.float32(0.0))
    balance = distance_balance(ctx, r).astype(np.float32)
    var_ring = None
    if var is not None and ctx.weighting == "relative":  # σ²: ring means of the data's variance
        var_ring = ring_means(rings, valid, var).astype(np.float32)
    rel2 = np.float32(ctx.rho**2)
    if var is not None and ctx.weighting == "poisson":  # σ² = v₀ αP with v₀ = Σ var / Σ y of the
        # window (= 1/(N p²) for photon counts, whose variance is y/(N p²)); windows without any
        # variance are noise-free: every weighting fits them alike, and they take the relative error ρ
        v_sum = var.sum(axis=(1, 2), dtype=np.float64)
        y_sum = y.sum(axis=(1, 2), dtype=np.float64)
        noisy = (v_sum > 0) & (y_sum > 0)
        poisson = np.where(noisy, v_sum / np.where(noisy, y_sum, 1.0), 0.0).astype(np.float32)[:, None, None]
        rel2 = np.where(noisy, 0.0, ctx.rel_sigma**2).astype(np.float32)[:, None, None]
    usable = (valid.sum(axis=1) >= 2 * ctx.n + 2) & (y.sum(axis=(1, 2), dtype=np.float64) > 0)
    # windows with noise: a photon count (Poisson factor > 0) or a variance
    p_k = np.asarray(poisson)
    noisy = (np.broadcast_to(p_k, (k,) + p_k.shape[1:]) > 0).reshape(k, -1).any(axis=1)
    if var is not None:
        noisy |= var.sum(axis=(1, 2), dtype=np.float64) > 0
    return Chunk(
        y=y,
        valid=valid,
        balance=balance,
        var_ring=var_ring,
        r=r.astype(np.float32),
        theta=theta,
        gid=gid.astype(np.int32),
        r_g=r_g,
        r_base=r_base,
        rings=rings,
        base=base,
        local=local,
        usable=usable,
        poisson=poisson,
        rel2=rel2,
        first=s,
        noisy=noisy,
        total_bound=ctx.source.total_bound(s, e) if hasattr(ctx.source, "total_bound") else None,
    )


def load_chunk(ctx: FitContext, state: FitState, s: int, e: int, raw=None) -> Chunk:
    """Points s..e from the cache of earlier rounds (or ``raw``, or the source), with the current α."""
    ch = ctx.cache.get((s, e))
    if ch is None:
        ch = prepare_chunk(ctx, s, e, raw)
        nbytes = sum(
            np.asarray(a).nbytes
            for a in (ch.y, ch.valid, ch.balance, ch.local, ch.r, ch.theta, ch.gid, ch.poisson)
        )
        if ctx.cache_left >= nbytes:
            ctx.cache_left -= nbytes
            ctx.cache[(s, e)] = ch
    return replace(ch, alpha=ch.per_channel(state.alpha.astype(np.float32).ravel()[ch.pixel]))


def weights(ctx: FitContext, ch: Chunk, model: np.ndarray | None) -> np.ndarray:
    r"""w² per pixel and channel (module docstring) for the model prediction αP, (k, J, 3) (overwritten).

    The variance is taken from a model, never from the pixel's own value: a
    pixel-wise estimate is proportional to the noisy count (Poisson), and
    weighting by it would pull the fit below the data where counts are few.
    ``model`` None (round 1): ring means of the data stand in for αP.
    """
    if model is None:  # round 1: ring means of y/α stand in for the model
        safe = np.where(ch.alpha > 0, ch.alpha, np.float32(1.0))
        model = ch.rings.spread(ring_means(ch.rings, ch.valid, ch.y / safe).astype(np.float32))
        model *= ch.alpha
    k = model.shape[0]  # floor: 10⁻⁶ of each window's peak (keeps the weights finite)
    floor = np.maximum(1e-6 * model.reshape(k, -1).max(axis=1), np.float32(1e-15))
    np.maximum(model, floor[:, None, None], out=model)
    # w² = static / (αP (ρ² αP + v₀)) with v₀ = 1/(N p²) (ρ = 0: "poisson"), or ρ²(αP)² + σ̄² with
    # the data's ring-mean variance σ̄² ("relative" without a photon count); in place: these are the
    # largest arrays of a chunk
    den = np.multiply(model, ch.rel2)
    if ch.var_ring is None:
        den += ch.poisson
        den *= model
    else:
        den *= model
        den += ch.rings.spread(ch.var_ring)
    del model
    w2 = ch.per_channel(ch.static)
    w2 /= den  # den > 0: the model is floored
    return w2


def objective(w2: np.ndarray, model: np.ndarray, y: np.ndarray) -> float:
    """Φ = Σ w² (αP − y)² of a chunk (float64 sum)."""
    res = model - y
    res *= res
    res *= w2
    return float(np.sum(res, dtype=np.float64))
