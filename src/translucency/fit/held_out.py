"""The held-out split of a planar fit: two interleaved halves of every window's pairs, one fitted and the
other scored (:func:`pair_half`, :func:`held_out_error`); the choice of n and m by it is
:func:`translucency.fit.planar.select_model`.

A pair is (incident point i, sample-grid pixel); its half is (row + col + i) mod 2, a checkerboard over
each window flipped from one point to the next, so every pixel is fitted from some windows and scored in
the others.  Errors are relative L2, ‖αP − y‖ / ‖y‖ (dimensionless).
"""

from __future__ import annotations

import numpy as np

from ..geometry import SampleGrid, window_geometry
from ..io.dataset import PlanarDataset
from .options import FitResult

__all__ = ["held_out_error", "pair_half"]


def pair_half(i, pixel, grid: SampleGrid) -> np.ndarray:
    """The half (0 or 1) of each pair (point i (k,), sample-grid pixel (k, J)): (row + col + i) mod 2."""
    return (pixel // grid.shape[1] + pixel % grid.shape[1] + np.asarray(i)[:, None]) % 2


def held_out_error(fit: FitResult, ds: PlanarDataset, *, near: float = 0.0, chunk_points: int = 256) -> float:
    """Relative L2 error ‖αP − y‖ / ‖y‖ of a fit made on one ``half`` over the other half's pairs.

    α at a held-out pair's pixel comes from the windows where that pixel was
    fitted; pixels no fitted pair covers take the mean α of their fitted
    4-neighbours.  Pairs as in the fit (mask set, finite, flagged points left
    out), from the smallest radius the fit saw in each window on: the halves
    interleave, so the first held-out ring may lie inside the first fitted one,
    and a profile is not asked to extrapolate towards x_i.

    Examples
    --------
    >>> e = held_out_error(fit_planar(ds, "iso", half=0), ds)   # doctest: +SKIP
    """
    model, fitted = fit.model, int(fit.options["half"])
    grid = SampleGrid.covering(ds["window_origin"].astype(np.float64), ds.pitch, ds.window)
    x_i = ds["x_i"].astype(np.float64)
    origin = ds["window_origin"].astype(np.float64)
    exclusion = float(fit.options.get("exclusion_mm", ds.pitch))

    def pairs(s, e):  # data, geometry and the valid pairs of points s..e (both halves)
        k = e - s
        y = ds.read("R_d", s, e).astype(np.float64).reshape(k, -1, 3)
        geom = window_geometry(x_i[s:e], origin[s:e], grid, ds.window)
        r, theta = (np.broadcast_to(a, (k, y.shape[1])) for a in (geom.r, geom.theta))
        pixel = np.broadcast_to(geom.pixel, r.shape)
        valid = ds.read("mask", s, e).reshape(k, -1) & np.isfinite(y).all(axis=2) & (r >= exclusion)
        valid &= ~fit.flagged[s:e, None]
        return y, r, theta, pixel, valid, pair_half(np.arange(s, e), pixel, grid) == fitted

    chunks = [(s, min(s + chunk_points, ds.n_points)) for s in range(0, ds.n_points, chunk_points)]
    # the pixels some fitted pair covers; the others take their fitted neighbours' mean α
    seen = np.zeros(grid.shape[0] * grid.shape[1], dtype=bool)
    for s, e in chunks:
        _, _, _, pixel, valid, train = pairs(s, e)
        seen[pixel[valid & train]] = True
    seen = seen.reshape(grid.shape)
    alpha = np.asarray(model.alpha.values, dtype=np.float64)
    pad_seen = np.pad(seen, 1).astype(np.float64)
    padded = np.pad(alpha, 1) * pad_seen
    num = padded[:-2, 1:-1] + padded[2:, 1:-1] + padded[1:-1, :-2] + padded[1:-1, 2:]
    cnt = pad_seen[:-2, 1:-1] + pad_seen[2:, 1:-1] + pad_seen[1:-1, :-2] + pad_seen[1:-1, 2:]
    alpha = np.where(seen, alpha, num / np.maximum(cnt, 1.0)).ravel()
    sq_err = sq_data = 0.0
    for s, e in chunks:
        y, r, theta, pixel, valid, train = pairs(s, e)
        # no inward extrapolation: held-out pairs from the smallest radius the fit saw in the window on
        r_fit = np.where(valid & train, r, np.inf).min(axis=1, keepdims=True)
        test = valid & ~train & (r >= np.maximum(r_fit, near))
        i = np.broadcast_to(np.arange(s, e)[:, None], r.shape)
        pred = alpha[pixel[test]][:, None] * model.profile(i[test], r[test], theta[test])
        sq_err += float(np.sum((pred - y[test]) ** 2))
        sq_data += float(np.sum(y[test] ** 2))
    return float(np.sqrt(sq_err / max(sq_data, 1e-300)))
