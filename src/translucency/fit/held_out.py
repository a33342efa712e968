"""The held-out split of a fit: two interleaved halves of the pairs (incident point, pixel or vertex), one
fitted and the other scored, per incident point so that two fits' scores have a standard error.

*Planar* (:func:`pair_half`): a pair is (incident point i, sample-grid pixel); its half is
(row + col + i) mod 2, a checkerboard over each window flipped from one point to the next, so every pixel is
fitted from some windows and scored in the others.  *Mesh* (:func:`vertex_half`): a pair is (incident point
i, vertex v); its half is (v + i) mod 2, so every vertex is fitted from half the points and scored from the
others.  Errors are relative L2, ‖αP − y‖ / ‖y‖ (dimensionless); :func:`held_out_terms` and
:func:`mesh_held_out_terms` give each point's ‖αP − y‖² and ‖y‖² (mm⁻⁴ times the pairs' count), whose sums
make :func:`held_out_error` and whose differences between two fits make the split's noise
(:mod:`translucency.fit.structure`).
"""

from __future__ import annotations

import numpy as np

from ..geometry import SampleGrid, window_geometry
from ..io.dataset import PlanarDataset
from .mesh_pairs import read_pairs
from .options import FitResult

__all__ = ["held_out_error", "held_out_terms", "mesh_held_out_terms", "pair_half", "vertex_half"]


def pair_half(i, pixel, grid: SampleGrid) -> np.ndarray:
    """The half (0 or 1) of each pair (point i (k,), sample-grid pixel (k, J)): (row + col + i) mod 2."""
    return (pixel // grid.shape[1] + pixel % grid.shape[1] + np.asarray(i)[:, None]) % 2


def vertex_half(i, vertex) -> np.ndarray:
    """The half (0 or 1) of each pair (point i (k,), vertex (k, V) or (V,)): (v + i) mod 2.

    Examples
    --------
    >>> vertex_half(np.array([0, 1]), np.arange(4)).tolist()
    [[0, 1, 0, 1], [1, 0, 1, 0]]
    """
    return (np.asarray(vertex) + np.asarray(i)[:, None]) % 2


def held_out_error(fit: FitResult, ds: PlanarDataset, *, near: float = 0.0, chunk_points: int = 32) -> float:
    """Relative L2 error ‖αP − y‖ / ‖y‖ of a planar fit made on one ``half`` over the other half's pairs
    (:func:`held_out_terms` summed over the points).

    Examples
    --------
    >>> e = held_out_error(fit_planar(ds, "iso", half=0), ds)   # doctest: +SKIP
    """
    sq_err, sq_data = held_out_terms(fit, ds, near=near, chunk_points=chunk_points)
    return float(np.sqrt(sq_err.sum() / max(sq_data.sum(), 1e-300)))


def held_out_terms(fit: FitResult, ds: PlanarDataset, *, near: float = 0.0, chunk_points: int = 32):
    """Per incident point, ‖αP − y‖² and ‖y‖² over the held-out half of its pairs (planar), (P,) each.

    α at a held-out pair's pixel comes from the windows where that pixel was
    fitted; pixels no fitted pair covers take the mean α of their fitted
    4-neighbours.  Pairs as in the fit (mask set, finite, flagged points left
    out: their terms are 0), from the smallest radius the fit saw in each window on:
    the halves interleave, so the first held-out ring may lie inside the first fitted one,
    and a profile is not asked to extrapolate towards x_i; and at least ``near`` mm from x_i.

    Examples
    --------
    >>> sq_err, sq_data = held_out_terms(fit_planar(ds, "iso", half=0), ds)   # doctest: +SKIP
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
    sq_err, sq_data = np.zeros(ds.n_points), np.zeros(ds.n_points)
    for s, e in chunks:
        y, r, theta, pixel, valid, train = pairs(s, e)
        # no inward extrapolation: held-out pairs from the smallest radius the fit saw in the window on
        r_fit = np.where(valid & train, r, np.inf).min(axis=1, keepdims=True)
        test = valid & ~train & (r >= np.maximum(r_fit, near))
        for k in range(e - s):  # one point at a time: its parameters broadcast over its pairs
            t = test[k]
            pred = alpha[pixel[k, t]][:, None] * model.profile(np.int64(s + k), r[k, t], theta[k, t])
            sq_err[s + k] = np.sum((pred - y[k, t]) ** 2)
            sq_data[s + k] = np.sum(y[k, t] ** 2)
    return sq_err, sq_data


def mesh_held_out_terms(fit: FitResult, group, *, chunk_points: int = 32):
    """Per incident point, ‖αP − y‖² and ‖y‖² over the held-out half of its pairs (mesh), (P,) each.

    A pair (i, v) is held out when :func:`vertex_half` differs from the fit's ``half``; pairs as the fit
    reads them (finite, at least the fit's exclusion radius from x_i, not flagged), each weighted by its
    vertex's area A_v (mm²), so that a finely meshed region does not count more than a coarse one.
    α at v was fitted from the other points' pairs on v (pooled over its disc).

    Examples
    --------
    >>> sq_err, sq_data = mesh_held_out_terms(fit_mesh("object.zarr", half=0), group)   # doctest: +SKIP
    """
    model, fitted = fit.model, int(fit.options["half"])
    vertices = np.asarray(group["vertices"][...], dtype=np.float64)
    area = np.asarray(group["vertex_area"][...], dtype=np.float64)
    alpha = np.asarray(model.alpha.values, dtype=np.float64)
    x_i = np.asarray(model.x_i, dtype=np.float64)
    P = len(x_i)
    sq_err, sq_data = np.zeros(P), np.zeros(P)
    for s in range(0, P, chunk_points):
        e = min(s + chunk_points, P)
        y, r, valid = read_pairs(group, vertices, x_i, float(fit.options["exclusion_mm"]), s, e)
        test = valid & (vertex_half(np.arange(s, e), np.arange(len(vertices))) != fitted)
        test &= ~fit.flagged[s:e, None]
        for k in range(e - s):  # one point at a time: its parameters broadcast over its (V, 3) pairs
            t = test[k]
            pred = alpha[t, None] * model.profile(np.int64(s + k), r[k, t], np.zeros(t.sum()))
            sq_err[s + k] = np.sum(area[t, None] * (pred - y[k, t]) ** 2)
            sq_data[s + k] = np.sum(area[t, None] * y[k, t].astype(np.float64) ** 2)
    return sq_err, sq_data
