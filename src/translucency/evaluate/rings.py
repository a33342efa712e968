"""Ring means around an incident point: of a measured window (one-pixel rings) and of a model (any rings).

:func:`ring_stats` averages a window centred on x_i over rings one pixel wide, with the standard error of
each mean; :func:`model_rings` averages a model's R_d over the rings of any radial grid (the fine
near-x_i profiles).  Radii in mm, R_d in mm⁻².
"""

from __future__ import annotations

import numpy as np


def ring_stats(window: np.ndarray, variance: np.ndarray | None, pitch: float):
    """Ring means of a (H, W) window centred on x_i and the standard error of each mean.

    Rings one pixel wide, pixel (row, col) in ring round(hypot(col − W//2, row − H//2)), r ≥ one pixel
    (the pixel under the beam is left out, as the fits' exclusion radius does); returns (r in mm, mean
    R_d, standard error of the mean), the error sqrt(Σ σ²)/n of the ring's pixels (zeros without a
    ``variance``).

    Examples
    --------
    >>> r, mean, err = ring_stats(np.ones((5, 5)), None, 0.5)
    >>> r.tolist(), mean.tolist(), err.tolist()
    ([0.5, 1.0], [1.0, 1.0], [0.0, 0.0])
    """
    h, w = window.shape
    yy, xx = np.mgrid[0:h, 0:w]
    ring = np.round(np.hypot(xx - w // 2, yy - h // 2)).astype(int).ravel()
    n = min(h, w) // 2 + 1
    cnt = np.bincount(ring, minlength=n)[:n]
    sums = np.bincount(ring, window.ravel(), minlength=n)[:n]
    var = np.zeros(n) if variance is None else np.bincount(ring, variance.ravel(), minlength=n)[:n]
    keep = (np.arange(n) >= 1) & (cnt > 0)
    count = cnt[keep]
    return np.arange(n)[keep] * pitch, sums[keep] / count, np.sqrt(var[keep]) / count


def model_rings(model, point: int, edges: np.ndarray, channel: int = 1, samples: int = 8, angles: int = 64):
    """Area-weighted mean of a model's R_d (α(x_o) included) over each ring [edges[j], edges[j+1]) around
    its incident point ``point``: the ring means of a fine radial grid."""
    x0 = np.asarray(model.x_i[point, :2], dtype=np.float64)
    lo, hi = edges[:-1], edges[1:]
    t = (np.arange(samples) + 0.5) / samples
    r = lo[:, None] + (hi - lo)[:, None] * t[None, :]  # (J, S)
    phi = 2 * np.pi * (np.arange(angles) + 0.5) / angles
    xo = x0 + np.stack([r[..., None] * np.cos(phi), r[..., None] * np.sin(phi)], axis=-1)  # (J, S, A, 2)
    vals = model.R_d(np.full(xo[..., 0].size, point), xo.reshape(-1, 2))[:, channel].reshape(
        r.shape + (angles,)
    )
    return (vals.mean(axis=2) * r).sum(axis=1) / r.sum(axis=1)
