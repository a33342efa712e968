r"""Batched variable-projection fit of sums of exponentials (the planar fitters' hot path).

B independent problems, each a weighted profile on the same G radii:

.. math:: \min_{c \ge 0,\; a > 0} \sum_g W_{bg}^2
          \Bigl(\sum_{k=1}^{n} c_{bk} e^{-a_{bk} r_g} - Y_{bg}\Bigr)^2 .

For fixed rates :math:`a` the amplitudes are a non-negative least-squares
problem in n unknowns; with n ≤ 4 it is solved exactly by trying every
support set (the NNLS optimum is the unconstrained optimum on its support).
Everything is expressed through the moments

.. math:: K^{(p)}_{kl} = \sum_g W_g^2 r_g^p e^{-(a_k+a_l) r_g},\qquad
          k^{(p)}_k = \sum_g W_g^2 r_g^p e^{-a_k r_g} Y_g, \qquad p = 0, 1, 2,

so one evaluation costs a few batched matrix products over the radii.  The
rates move by Levenberg–Marquardt on the joint Gauss–Newton system of
:math:`(c, \log a)` (Jacobian columns :math:`e^{-a_k r}` and
:math:`-a_k c_k r e^{-a_k r}`), and the amplitudes are re-projected after
every step: a step is kept where the projected cost falls.  No Python loop
runs over problems; the loop is over iterations.
"""

from __future__ import annotations

import numpy as np


def _weights(r, W2, Y):
    """What the moments need that does not depend on the rates (computed once per block).

    ``Wr`` (B, G, 3) holds :math:`W^2 r^p` for p = 0, 1, 2 and ``Wy`` (B, G, 2)
    holds :math:`W^2 r^p Y` for p = 0, 1.
    """
    Wr = np.stack([W2, W2 * r, W2 * r * r], axis=2)
    Wy = np.stack([W2 * Y, W2 * r * Y], axis=2)
    return Wr, Wy


def _moments(r, Wr, Wy, a):
    """K^(p) for p = 0, 1, 2 as (3, B, n, n) and k^(p) for p = 0, 1 as (2, B, n)."""
    B, n = a.shape
    E = np.exp(-a[:, :, None] * r[None, None, :])  # (B, n, G)
    pairs = [(k, l) for k in range(n) for l in range(k, n)]
    EE = np.empty((B, len(pairs), r.size))
    for j, (k, l) in enumerate(pairs):
        np.multiply(E[:, k], E[:, l], out=EE[:, j])
    Kp = np.matmul(EE, Wr)  # (B, pairs, 3)
    K = np.empty((3, B, n, n))
    for j, (k, l) in enumerate(pairs):
        K[:, :, k, l] = K[:, :, l, k] = Kp[:, j].T
    kp = np.matmul(E, Wy)  # (B, n, 2)
    return K, kp.transpose(2, 0, 1)


def nnls_small(K: np.ndarray, k: np.ndarray, YY: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact batched NNLS for tiny n from the normal equations.

    Minimises :math:`c^T K c - 2 c^T k + YY` over :math:`c \\ge 0` for each of B
    problems by solving the unconstrained problem on every support set and
    keeping the best feasible one.

    Parameters
    ----------
    K : ndarray, shape (B, n, n)
    k : ndarray, shape (B, n)
    YY : ndarray, shape (B,)

    Returns
    -------
    c : ndarray, shape (B, n)
    cost : ndarray, shape (B,)

    Examples
    --------
    >>> K = np.array([[[2.0, 1.0], [1.0, 2.0]]]); k = np.array([[3.0, -1.0]])
    >>> c, cost = nnls_small(K, k, np.array([5.0]))
    >>> c.round(6), cost.round(6)
    (array([[1.5, 0. ]]), array([0.5]))
    """
    B, n, _ = K.shape
    ridge = 1e-12 * np.maximum(np.einsum("bkk->b", K), 1e-300)
    # where the unconstrained optimum is non-negative it is the NNLS optimum (convex problem)
    c = np.linalg.solve(K + ridge[:, None, None] * np.eye(n), k[..., None])[..., 0]
    feasible = (c >= 0).all(axis=1)
    if feasible.all():
        return c, np.maximum(YY - np.einsum("bk,bk->b", c, k), 0.0)
    if feasible.any():
        rest = ~feasible
        c_rest, cost_rest = nnls_small(K[rest], k[rest], YY[rest])
        cost = np.maximum(YY - np.einsum("bk,bk->b", c, k), 0.0)
        c[rest], cost[rest] = c_rest, cost_rest
        return c, cost
    # every non-empty support S as a mask; on S solve K_SS c_S = k_S, elsewhere c = 0
    # (identity rows/columns off S), all supports in one batched solve
    supports = np.array([[(mask >> j) & 1 for j in range(n)] for mask in range(1, 2**n)], dtype=bool)
    on = supports[:, None, :, None] & supports[:, None, None, :]  # (S, 1, n, n)
    KS = np.where(on, K[None] + ridge[None, :, None, None] * np.eye(n), np.eye(n))
    kS = np.where(supports[:, None, :], k[None], 0.0)
    cS = np.linalg.solve(KS, kS[..., None])[..., 0]  # (S, B, n)
    cost = YY[None] - np.einsum("sbk,sbk->sb", cS, kS)
    cost = np.where((cS >= 0).all(axis=2), cost, np.inf)
    best = np.argmin(cost, axis=0)
    best_cost = np.take_along_axis(cost, best[None], 0)[0]
    best_c = np.take_along_axis(cS, best[None, :, None], 0)[0]
    empty = ~(best_cost < YY)  # the empty support (c = 0, cost = YY) wins
    best_c[empty] = 0.0
    best_cost = np.where(empty, YY, best_cost)
    return best_c, np.maximum(best_cost, 0.0)


def _initial_rates(lo: float, hi: float, n: int, start: int, n_starts: int) -> np.ndarray:
    """Rates spread geometrically over [lo, hi] (log space), shifted a little per start."""
    frac = (np.arange(n) + 0.5 + 0.5 * (start - (n_starts - 1) / 2) / max(n_starts, 1)) / n
    return np.exp(lo + (hi - lo) * np.clip(frac, 0.05, 0.95))


def rate_bounds(r: np.ndarray) -> tuple[float, float]:
    """Log-rate bounds the radii can resolve.

    From 0.5/span (a slower decay is indistinguishable from a constant and would
    inflate the total 2π Σ c/a²) to 8/r_min (the term has fallen to e⁻⁸ at the
    first sample beyond r = 0).
    """
    r = np.asarray(r, dtype=np.float64)
    span = max(float(r.max() - r.min()), 1e-6)
    r_min = float(r[r > 0].min()) if (r > 0).any() else span
    return float(np.log(0.5 / span)), float(np.log(8.0 / max(r_min, 1e-6)))


def fit_exponentials_batched(r, W, Y, n_terms: int, *, rates0=None, n_starts: int = 3, pooled: bool = False,
                             max_iter: int = 50, tol: float = 1e-7, bounds=None, block: int = 1024):
    """Fit :math:`\\sum_k c_k e^{-a_k r}` to B weighted profiles at once.

    Parameters
    ----------
    r : ndarray, shape (G,)
        Radii in mm, shared by all problems.
    W : ndarray, shape (B, G)
        Residual weights (0 drops a radius from a problem).
    Y : ndarray, shape (B, G)
        Targets.
    n_terms : int
        Number of terms n (≤ 4).
    rates0 : ndarray, shape (B, n) or (S, B, n), optional
        Warm start(s) (rates > 0, mm⁻¹); otherwise ``n_starts`` spread starts.
    pooled : bool
        Without ``rates0``: first fit the pooled profile of all B problems
        (:math:`\\sum W^2 Y / \\sum W^2`) from the ``n_starts`` spread starts,
        then start every problem from its rates and from a spread-out variant
        of them — neighbouring points have similar profiles, so this converges
        in a fraction of the iterations of spread starts.
    bounds : (float, float), optional
        Bounds on log rates; default :func:`rate_bounds` of ``r``.
    block : int
        Problems solved together; blocks of a few hundred keep the (block, G, n)
        work arrays in cache, which is several times faster than one huge batch.

    Returns
    -------
    c : ndarray, shape (B, n)
        Amplitudes ≥ 0, terms sorted by decreasing rate.
    a : ndarray, shape (B, n)
        Rates > 0 in mm⁻¹ (the model's d = −a).
    cost : ndarray, shape (B,)
        :math:`\\sum_g W^2 (f - Y)^2` at the solution.

    Examples
    --------
    >>> r = np.linspace(0.1, 8, 120)
    >>> Y = np.stack([0.5 * np.exp(-3 * r) + 0.05 * np.exp(-0.4 * r), 0.2 * np.exp(-1.0 * r)])
    >>> c, a, cost = fit_exponentials_batched(r, 1 / Y, Y, 2)
    >>> a[0].round(5), a[1, 1].round(5), c[1].round(5)
    (array([3. , 0.4]), np.float64(1.0), array([0. , 0.2]))
    """
    r = np.asarray(r, dtype=np.float64)
    W2 = np.asarray(W, dtype=np.float64) ** 2
    Y = np.asarray(Y, dtype=np.float64)
    B, n = Y.shape[0], int(n_terms)
    bounds = bounds if bounds is not None else rate_bounds(r)
    # problems without data (all weights 0) get c = 0 and unit rates
    out = [np.zeros((B, n)), np.ones((B, n)), np.zeros(B)]
    todo = np.flatnonzero((W2 > 0).any(axis=1))
    if rates0 is None and pooled and todo.size > 1:
        w2 = W2[todo].sum(axis=0)
        y_pool = np.divide((W2[todo] * Y[todo]).sum(axis=0), w2, out=np.zeros_like(w2), where=w2 > 0)
        _, a_pool, _ = _fit_block(r, w2[None], y_pool[None], n, None, n_starts, 2 * max_iter, tol, bounds)
        spread = np.exp(np.linspace(0.7, -0.7, n))  # steeper terms steeper, flatter flatter
        rates0 = np.stack([np.broadcast_to(a_pool, (B, n)), np.broadcast_to(a_pool * spread, (B, n))])
    if rates0 is not None:
        rates0 = np.asarray(rates0, dtype=np.float64)
        rates0 = rates0[None] if rates0.ndim == 2 else rates0
    for s in range(0, todo.size, block):
        rows = todo[s:s + block]
        res = _fit_block(r, W2[rows], Y[rows], n, None if rates0 is None else rates0[:, rows],
                         n_starts, max_iter, tol, bounds)
        for o, x in zip(out, res):
            o[rows] = x
    return tuple(out)


_PROBE_ITER = 4  # iterations from every start before the best start per problem is kept


def _fit_block(r, W2, Y, n, rates0, n_starts, max_iter, tol, bounds):
    B = Y.shape[0]
    lo, hi = bounds
    YY = np.einsum("bg,bg->b", W2, Y * Y)
    Wr, Wy = _weights(r, W2, Y)
    if rates0 is not None:
        starts = [np.log(np.clip(r0, np.exp(lo), np.exp(hi))) for r0 in rates0]
    else:
        starts = [np.broadcast_to(np.log(_initial_rates(lo, hi, n, s, n_starts)), (B, n)).copy()
                  for s in range(n_starts)]
    # several starts: a few iterations from each, then only the best one per problem goes on
    probe = max_iter if len(starts) == 1 else min(max_iter, _PROBE_ITER)
    best = None
    for theta in starts:
        sol = _lm(r, Wr, Wy, YY, theta, lo, hi, probe, tol)
        if best is None:
            best = sol
        else:
            better = sol[2] < best[2]
            best = tuple(np.where(better[:, None] if x.ndim == 2 else better, x, y) for x, y in zip(sol, best))
    if probe < max_iter:
        best = _lm(r, Wr, Wy, YY, np.log(best[1]), lo, hi, max_iter - probe, tol)
    c, a, cost = best
    order = np.argsort(-a, axis=1)
    return np.take_along_axis(c, order, 1), np.take_along_axis(a, order, 1), cost


def _lm(r, Wr, Wy, YY, theta, lo, hi, max_iter, tol):
    """Levenberg–Marquardt over θ = log a with amplitudes re-projected (see module doc).

    Problems that have converged leave the working set, so late iterations
    cost only what is still moving.
    """
    B, n = theta.shape
    lam = np.full(B, 1e-3)
    (K0, K1, K2), (k0, k1) = _moments(r, Wr, Wy, np.exp(theta))
    c, cost = nnls_small(K0, k0, YY)
    active = np.arange(B)
    eye = np.eye(2 * n)
    for _ in range(max_iter):
        if active.size == 0:
            break
        i = active
        a = np.exp(theta[i])
        ac = a * c[i]  # ∂f/∂θ_k = −a_k c_k r e^{−a_k r}
        # Gauss–Newton system of the joint (c, θ) problem from the moments
        JTJ = np.empty((i.size, 2 * n, 2 * n))
        JTJ[:, :n, :n] = K0[i]
        JTJ[:, :n, n:] = -K1[i] * ac[:, None, :]
        JTJ[:, n:, :n] = -K1[i] * ac[:, :, None]
        JTJ[:, n:, n:] = K2[i] * ac[:, :, None] * ac[:, None, :]
        g = np.concatenate([np.einsum("bkl,bl->bk", K0[i], c[i]) - k0[i],
                            -ac * (np.einsum("bkl,bl->bk", K1[i], c[i]) - k1[i])], axis=1)
        diag = np.einsum("bii->bi", JTJ)
        scale = diag.max(axis=1, keepdims=True)
        damp = lam[i, None] * (diag + 1e-9 * scale) + 1e-15 * scale
        step = np.linalg.solve(JTJ + damp[:, :, None] * eye, -g[:, :, None])[:, :, 0]
        trial = np.clip(theta[i] + step[:, n:], lo, hi)
        (tK0, tK1, tK2), (tk0, tk1) = _moments(r, Wr[i], Wy[i], np.exp(trial))
        tc, tcost = nnls_small(tK0, tk0, YY[i])
        better = tcost < cost[i]
        rel_gain = np.where(better, (cost[i] - tcost) / np.maximum(cost[i], 1e-300), 0.0)
        small_step = np.abs(trial - theta[i]).max(axis=1) < 1e-7
        # accept where the projected cost fell
        j = i[better]
        theta[j] = trial[better]
        K0[j], K1[j], K2[j], k0[j], k1[j] = tK0[better], tK1[better], tK2[better], tk0[better], tk1[better]
        c[j], cost[j] = tc[better], tcost[better]
        lam[i] = np.where(better, lam[i] / 3.0, lam[i] * 4.0)
        done = (better & ((rel_gain < tol) | small_step)) | (lam[i] > 1e10) | (cost[i] <= 1e-24 * YY[i])
        active = i[~done]
    return c, np.exp(theta), cost
