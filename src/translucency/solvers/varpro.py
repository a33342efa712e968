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

so one evaluation is one pass over the radii.  The rates move by
Levenberg–Marquardt on the joint Gauss–Newton system of
:math:`(c, \log a)` (Jacobian columns :math:`e^{-a_k r}` and
:math:`-a_k c_k r e^{-a_k r}`), and the amplitudes are re-projected after
every step: a step is kept where the projected cost falls.

The per-problem work (moments, NNLS, the 2n × 2n step) is a small compiled
kernel (Numba, ``nogil``): plain loops, each problem on its own, with no
Python in between — several times faster than the same algorithm batched
in NumPy, whose many small array operations per iteration cost more than
their arithmetic.
"""

from __future__ import annotations

import numpy as np
from numba import njit


# -- per-problem kernels (compiled by Numba, GIL released: chunks fit in parallel threads) --------
@njit(cache=True, nogil=True)
def _solve_small(A, b, x):
    """x = A⁻¹ b for a small dense system (Gaussian elimination, partial pivoting; A, b overwritten)."""
    m = b.shape[0]
    for col in range(m):
        piv = col
        for row in range(col + 1, m):
            if abs(A[row, col]) > abs(A[piv, col]):
                piv = row
        if piv != col:
            for j in range(m):
                A[col, j], A[piv, j] = A[piv, j], A[col, j]
            b[col], b[piv] = b[piv], b[col]
        d = A[col, col]
        if d == 0.0:
            d = 1e-300
            A[col, col] = d
        for row in range(col + 1, m):
            f = A[row, col] / d
            if f != 0.0:
                for j in range(col, m):
                    A[row, j] -= f * A[col, j]
                b[row] -= f * b[col]
    for row in range(m - 1, -1, -1):
        acc = b[row]
        for j in range(row + 1, m):
            acc -= A[row, j] * x[j]
        x[row] = acc / A[row, row]


@njit(cache=True, nogil=True)
def _exponentials(r, base, a, E):
    r"""E[k, g] = :math:`e^{-a_k r_g}` for one problem.

    :math:`e^{-a r_g} = e^{-a b_g} e^{-a (r_g - b_g)}`: on equally spaced base radii
    :math:`b_g` the first factor follows from the last by one product, the
    second is a short series in the small offset (to x⁷ for |a (r − b)| ≤ 1/4,
    relative error < 1e-9; beyond, the exponential is taken exactly).
    """
    n, G = E.shape
    for k in range(n):
        ak = a[k]
        eb, q, step = 1.0, 1.0, -1.0  # e^{−a b_g}, e^{−a step}, current spacing of the base radii
        for g in range(G):
            bg = base[g]
            d = bg - base[g - 1] if g > 0 else -1.0
            if g > 0 and abs(d - step) <= 1e-12 * bg:
                eb *= q
            else:
                eb = np.exp(-ak * bg)
                if g > 0:
                    step = d
                    q = np.exp(-ak * d)
            x = -ak * (r[g] - bg)
            if x == 0.0:
                E[k, g] = eb
            elif abs(x) <= 0.25:
                E[k, g] = eb * (
                    1.0
                    + x
                    * (
                        1.0
                        + x
                        * (
                            0.5
                            + x
                            * (
                                1.0 / 6.0
                                + x
                                * (1.0 / 24.0 + x * (1.0 / 120.0 + x * (1.0 / 720.0 + x * (1.0 / 5040.0))))
                            )
                        )
                    )
                )
            else:  # a steep term far off its base: exactly
                E[k, g] = np.exp(-ak * r[g])


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _moments(r, base, w2, y, a, E, K0, K1, K2, k0, k1):
    r"""K^(p) (p = 0, 1, 2) and k^(p) (p = 0, 1) of one problem at rates a (module docstring).

    Sums over the radii as plain reductions (vectorised by the compiler).
    """
    n, G = E.shape
    _exponentials(r, base, a, E)
    for k in range(n):
        s0 = s1 = 0.0
        for g in range(G):
            t = w2[g] * y[g] * E[k, g]
            s0 += t
            s1 += t * r[g]
        k0[k], k1[k] = s0, s1
        for l in range(k, n):
            s0 = s1 = s2 = 0.0
            for g in range(G):
                t = w2[g] * E[k, g] * E[l, g]
                s0 += t
                s1 += t * r[g]
                s2 += t * r[g] * r[g]
            K0[k, l] = K0[l, k] = s0
            K1[k, l] = K1[l, k] = s1
            K2[k, l] = K2[l, k] = s2


@njit(cache=True, nogil=True)
def _nnls(K, k, YY, c):
    """Exact NNLS of c^T K c − 2 c^T k + YY over c ≥ 0 (every support; the full one first); returns the
    cost."""
    n = k.shape[0]
    ridge = 0.0
    for i in range(n):
        ridge += K[i, i]
    ridge = 1e-12 * max(ridge, 1e-300)
    A = np.empty((n, n))
    b = np.empty(n)
    x = np.empty(n)
    idx = np.empty(n, np.int64)
    bb = np.empty(n)
    best = YY  # the empty support: c = 0
    c[:] = 0.0
    full = (1 << n) - 1
    for t in range(full):
        mask = full - t  # the full support first: where it is feasible it is the optimum
        m = 0
        for i in range(n):
            if (mask >> i) & 1:
                idx[m] = i
                m += 1
        for i in range(m):
            for j in range(m):
                A[i, j] = K[idx[i], idx[j]]
            A[i, i] += ridge
            b[i] = bb[i] = k[idx[i]]
        _solve_small(A[:m, :m], b[:m], x[:m])
        feasible = True
        cost = YY
        for i in range(m):
            if x[i] < 0.0:
                feasible = False
            cost -= x[i] * bb[i]
        if feasible and cost < best:
            best = cost
            c[:] = 0.0
            for i in range(m):
                c[idx[i]] = x[i]
            if mask == full:
                break
    return max(best, 0.0)


@njit(cache=True, nogil=True)
def _lm(r, base, W2, Y, YY, theta, lo, hi, max_iter, tol):
    """Levenberg–Marquardt over θ = log a with amplitudes re-projected, problem by problem (module doc)."""
    B, n = theta.shape
    c_out = np.zeros((B, n))
    cost_out = np.zeros(B)
    N = 2 * n
    K0, K1, K2 = np.empty((n, n)), np.empty((n, n)), np.empty((n, n))
    tK0, tK1, tK2 = np.empty((n, n)), np.empty((n, n)), np.empty((n, n))
    k0, k1, tk0, tk1 = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    c, tc, ac, a = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    JTJ, A = np.empty((N, N)), np.empty((N, N))
    g, rhs, step, trial = np.empty(N), np.empty(N), np.empty(N), np.empty(n)
    E = np.empty((n, r.shape[0]))
    for b in range(B):
        th = theta[b]
        for k in range(n):
            a[k] = np.exp(th[k])
        _moments(r, base, W2[b], Y[b], a, E, K0, K1, K2, k0, k1)
        cost = _nnls(K0, k0, YY[b], c)
        lam = 1e-3
        gain = 0.0
        for _ in range(max_iter):
            # Gauss–Newton system of the joint (c, θ) problem from the moments
            for k in range(n):
                ac[k] = a[k] * c[k]  # ∂f/∂θ_k = −a_k c_k r e^{−a_k r}
            for k in range(n):
                gk0, gk1 = -k0[k], -k1[k]
                for l in range(n):
                    JTJ[k, l] = K0[k, l]
                    JTJ[k, n + l] = -K1[k, l] * ac[l]
                    JTJ[n + k, l] = -K1[k, l] * ac[k]
                    JTJ[n + k, n + l] = K2[k, l] * ac[k] * ac[l]
                    gk0 += K0[k, l] * c[l]
                    gk1 += K1[k, l] * c[l]
                g[k] = gk0
                g[n + k] = -ac[k] * gk1
            scale = 0.0
            for i in range(N):
                scale = max(scale, JTJ[i, i])
            for i in range(N):
                for j in range(N):
                    A[i, j] = JTJ[i, j]
                A[i, i] += lam * (JTJ[i, i] + 1e-9 * scale) + 1e-15 * scale
                rhs[i] = -g[i]
            _solve_small(A, rhs, step)
            # the fall the Gauss–Newton model predicts, −(2 gᵀδ + δᵀ JᵀJ δ): below tol the
            # problem has converged, whether or not the step is taken
            pred = 0.0
            for i in range(N):
                q = 0.0
                for j in range(N):
                    q += JTJ[i, j] * step[j]
                pred -= 2.0 * g[i] * step[i] + step[i] * q
            flat = pred <= tol * cost
            move = 0.0
            for k in range(n):
                trial[k] = min(max(th[k] + step[n + k], lo), hi)
                move = max(move, abs(trial[k] - th[k]))
                a[k] = np.exp(trial[k])
            _moments(r, base, W2[b], Y[b], a, E, tK0, tK1, tK2, tk0, tk1)
            tcost = _nnls(tK0, tk0, YY[b], tc)
            better = tcost < cost
            if better:  # accept: the projected cost fell
                gain = (cost - tcost) / max(cost, 1e-300)
                th[:] = trial
                K0[:], K1[:], K2[:], k0[:], k1[:] = tK0, tK1, tK2, tk0, tk1
                c[:] = tc
                cost = tcost
                lam /= 3.0
            else:
                for k in range(n):
                    a[k] = np.exp(th[k])
                lam *= 4.0
            if (better and (gain < tol or move < 1e-7)) or flat or lam > 1e10 or cost <= 1e-24 * YY[b]:
                break
        c_out[b] = c
        cost_out[b] = cost
    return c_out, cost_out


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
    K, k, YY = (np.ascontiguousarray(x, dtype=np.float64) for x in (K, k, YY))
    c = np.zeros(k.shape)
    cost = np.array([_nnls(K[b], k[b], YY[b], c[b]) for b in range(len(YY))])
    return c, cost


def _initial_rates(lo: float, hi: float, n: int, start: int, n_starts: int) -> np.ndarray:
    """Rates spread geometrically over [lo, hi] (log space), shifted a little per start."""
    frac = (np.arange(n) + 0.5 + 0.5 * (start - (n_starts - 1) / 2) / max(n_starts, 1)) / n
    return np.exp(lo + (hi - lo) * np.clip(frac, 0.05, 0.95))


def rate_bounds(r: np.ndarray) -> tuple[float, float]:
    """Log-rate bounds the radii can resolve.

    From 0.5/span (a slower decay is indistinguishable from a constant and would
    inflate the total 2π Σ c/a²) to 8/r_min (the term has fallen to e⁻⁸ at the
    first sample beyond r = 0).

    Examples
    --------
    >>> lo, hi = rate_bounds(np.linspace(0.0, 8.0, 33))   # radii 0 to 8 mm, 0.25 mm apart
    >>> round(float(np.exp(lo)), 4), round(float(np.exp(hi)), 4)   # rates 0.5/8 to 8/0.25 mm⁻¹
    (0.0625, 32.0)
    """
    r = np.asarray(r, dtype=np.float64)
    span = max(float(r.max() - r.min()), 1e-6)
    r_min = float(r[r > 0].min()) if (r > 0).any() else span
    return float(np.log(0.5 / span)), float(np.log(8.0 / max(r_min, 1e-6)))


def fit_exponentials_batched(
    r,
    W,
    Y,
    n_terms: int,
    *,
    rates0=None,
    n_starts: int = 3,
    pooled: bool = False,
    max_iter: int = 50,
    tol: float = 1e-7,
    bounds=None,
    r_base=None,
):
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
    r_base : ndarray, shape (G,), optional
        Equally spaced radii near ``r`` (ring centres, :func:`._windows.radius_groups`)
        that make the exponentials cheap; default ``r``.

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
    base = r if r_base is None else np.asarray(r_base, dtype=np.float64)
    if base.shape != r.shape:
        raise ValueError("r_base: one base radius per radius")
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
        _, a_pool, _ = _fit_block(
            r, base, w2[None], y_pool[None], n, None, n_starts, 2 * max_iter, tol, bounds
        )
        spread = np.exp(np.linspace(0.7, -0.7, n))  # steeper terms steeper, flatter flatter
        rates0 = np.stack([np.broadcast_to(a_pool, (B, n)), np.broadcast_to(a_pool * spread, (B, n))])
    if rates0 is not None:
        rates0 = np.asarray(rates0, dtype=np.float64)
        rates0 = rates0[None] if rates0.ndim == 2 else rates0
    if todo.size:
        res = _fit_block(
            r,
            base,
            W2[todo],
            Y[todo],
            n,
            None if rates0 is None else rates0[:, todo],
            n_starts,
            max_iter,
            tol,
            bounds,
        )
        for o, x in zip(out, res):
            o[todo] = x
    return tuple(out)


_PROBE_ITER = 10  # iterations from every start before the best start per problem is kept


def _fit_block(r, base, W2, Y, n, rates0, n_starts, max_iter, tol, bounds):
    B = Y.shape[0]
    lo, hi = bounds
    YY = np.einsum("bg,bg->b", W2, Y * Y)
    if rates0 is not None:
        starts = [np.log(np.clip(r0, np.exp(lo), np.exp(hi))) for r0 in rates0]
    else:
        starts = [
            np.broadcast_to(np.log(_initial_rates(lo, hi, n, s, n_starts)), (B, n)).copy()
            for s in range(n_starts)
        ]
    # several starts: a few iterations from each, then only the best one per problem goes on
    probe = max_iter if len(starts) == 1 else min(max_iter, _PROBE_ITER)
    best = None
    for theta in starts:
        sol = _lm_rates(r, base, W2, Y, YY, theta, lo, hi, probe, tol)
        if best is None:
            best = sol
        else:
            better = sol[2] < best[2]
            best = tuple(
                np.where(better[:, None] if x.ndim == 2 else better, x, y) for x, y in zip(sol, best)
            )
    if probe < max_iter:
        best = _lm_rates(r, base, W2, Y, YY, np.log(best[1]), lo, hi, max_iter - probe, tol)
    c, a, cost = best
    order = np.argsort(-a, axis=1)
    return np.take_along_axis(c, order, 1), np.take_along_axis(a, order, 1), cost


def _lm_rates(r, base, W2, Y, YY, theta, lo, hi, max_iter, tol):
    """(c, a, cost) of every problem from log-rate starts θ (B, n), by the compiled LM."""
    theta = np.ascontiguousarray(theta, dtype=np.float64).copy()
    c, cost = _lm(
        r,
        base,
        np.ascontiguousarray(W2),
        np.ascontiguousarray(Y),
        YY,
        theta,
        float(lo),
        float(hi),
        int(max_iter),
        float(tol),
    )
    return c, np.exp(theta), cost
