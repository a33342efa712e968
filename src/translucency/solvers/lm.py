r"""Batched Levenberg–Marquardt for profiles with a few positive parameters (dipole, Burley).

B independent problems on the same G radii,

.. math:: \min_{p > 0} \sum_g W_{bg}^2 \bigl(f(r_g; p_b) - Y_{bg}\bigr)^2 ,

solved over :math:`\log p` (positivity for free) with a forward-difference
Jacobian — P + 1 evaluations of the vectorised profile per iteration for all
problems at once, and a per-problem damping that grows where a step fails.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np


def fit_params_batched(
    profile: Callable[[np.ndarray, np.ndarray], np.ndarray],
    r,
    W,
    Y,
    starts: Sequence[Sequence[float]],
    *,
    max_iter: int = 40,
    tol: float = 1e-10,
    block: int = 512,
) -> tuple[np.ndarray, np.ndarray]:
    """Fit ``profile(r, p)`` to B weighted profiles, trying every start and keeping the best.

    Parameters
    ----------
    profile : callable
        ``profile(r (G,), p (B, P)) -> (B, G)``, vectorised over problems.
    r : ndarray, shape (G,)
    W, Y : ndarray, shape (B, G)
        Weights and targets.
    starts : sequence of starting points (> 0)
        Each a vector of length P shared by all problems, or an array (B, P)
        with one start per problem (a warm start from earlier parameters).

    Returns
    -------
    p : ndarray, shape (B, P)
    cost : ndarray, shape (B,)

    Examples
    --------
    >>> r = np.linspace(0.1, 5, 50)
    >>> f = lambda r, p: p[:, :1] * np.exp(-p[:, 1:2] * r)
    >>> Y = f(r, np.array([[2.0, 0.5], [0.1, 3.0]]))
    >>> p, cost = fit_params_batched(f, r, 1 / Y, Y, [(1.0, 1.0)])
    >>> p.round(6)
    array([[2. , 0.5],
           [0.1, 3. ]])
    """
    r = np.asarray(r, dtype=np.float64)
    W = np.asarray(W, dtype=np.float64)
    Y = np.asarray(Y, dtype=np.float64)
    B = Y.shape[0]
    P = np.asarray(starts[0]).shape[-1]
    p_out, cost_out = np.empty((B, P)), np.full(B, np.inf)
    for s in range(0, B, block):
        sl = slice(s, s + block)
        for start in starts:
            start = np.asarray(start, dtype=np.float64)
            start = start[sl] if start.ndim == 2 else start
            x0 = np.broadcast_to(np.log(np.maximum(start, 1e-300)), (Y[sl].shape[0], P)).copy()
            x, cost = _lm(profile, r, W[sl], Y[sl], x0, max_iter, tol)
            better = cost < cost_out[sl]
            p_out[sl][better] = np.exp(x[better])
            cost_out[sl] = np.where(better, cost, cost_out[sl])
    return p_out, cost_out


def _residual(profile, r, W, Y, x):
    with np.errstate(over="ignore", under="ignore", invalid="ignore", divide="ignore"):
        res = W * (profile(r, np.exp(x)) - Y)
    return np.where(np.isfinite(res), res, 1e150)


def _lm(profile, r, W, Y, x, max_iter, tol):
    B, P = x.shape
    lam = np.full(B, 1e-3)
    res = _residual(profile, r, W, Y, x)
    cost = np.einsum("bg,bg->b", res, res)
    active = np.ones(B, dtype=bool)
    h = 1e-6
    for _ in range(max_iter):
        if not active.any():
            break
        # forward-difference Jacobian of the weighted residual w.r.t. log p
        J = np.stack(
            [(_residual(profile, r, W, Y, x + h * np.eye(P)[k]) - res) / h for k in range(P)], axis=2
        )
        JTJ = np.einsum("bgk,bgl->bkl", J, J)
        g = np.einsum("bgk,bg->bk", J, res)
        diag = np.einsum("bii->bi", JTJ)
        A = JTJ + (lam[:, None] * (diag + 1e-12 * diag.max(axis=1, keepdims=True)) + 1e-300)[
            :, :, None
        ] * np.eye(P)
        step = np.linalg.solve(A, -g[:, :, None])[:, :, 0]
        step = np.clip(step, -3.0, 3.0)
        trial = x + step
        t_res = _residual(profile, r, W, Y, trial)
        t_cost = np.einsum("bg,bg->b", t_res, t_res)
        better = active & (t_cost < cost)
        gain = np.where(better, (cost - t_cost) / np.maximum(cost, 1e-300), 0.0)
        x = np.where(better[:, None], trial, x)
        res = np.where(better[:, None], t_res, res)
        cost = np.where(better, t_cost, cost)
        lam = np.where(better, lam / 3.0, lam * 4.0)
        active &= ~((better & (gain < tol)) | (lam > 1e10))
    return x, cost
