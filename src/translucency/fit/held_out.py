r"""The held-out split of a fit: two interleaved halves of the pairs (incident point, pixel or vertex), one
fitted and the other scored, per incident point so that two fits' scores have a standard error.

*Planar* (:func:`pair_half`): a pair is (incident point i, sample-grid pixel); its half is
(row + col + i) mod 2, a checkerboard over each window flipped from one point to the next, so every pixel is
fitted from some windows and scored in the others.  *Mesh* (:func:`vertex_half`): a pair is (incident point
i, vertex v); its half is (v + i) mod 2, so every vertex is fitted from half the points and scored from the
others.  Errors are relative L2, ‖αP − y‖ / ‖y‖ (dimensionless); :func:`held_out_terms` and
:func:`mesh_held_out_terms` give each point's ‖αP − y‖² and ‖y‖² (mm⁻⁴ times the pairs' count), whose sums
make :func:`held_out_error` and whose differences between two fits make the split's noise
(:mod:`translucency.fit.structure`).

**Noise floor.**  The held-out half's own noise is independent of a model fitted on the other half, so over
the held-out pairs E‖αP − y‖² = ‖αP − ȳ‖² + Σσ² (ȳ the noise-free R_d, σ² each pair's variance, mm⁻⁴):
even the true profile scores :math:`\sqrt{\sum\sigma^2 / \sum y^2}`, the pairs' *noise*, and the held-out
error over that noise is 1 for a perfect model.  With ``variance=True`` both functions also give each
point's Σσ² over the same pairs, weighted as its error (planar: the data set's ``variance``; mesh: its
``R_d_var`` where it was measured from photographs, else the barycentric tally's variance of a simulated
one, :mod:`translucency.evaluate.mesh_errors`).
"""

from __future__ import annotations

import numpy as np

from ..geometry import SampleGrid, window_geometry
from ..io.dataset import PlanarDataset
from ..io.mesh_dataset import HEADER_KEY as MESH_HEADER_KEY
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
    The embedded scan fitted on one half of its pairs, scored on the other:

    >>> from translucency.data import default_dataset
    >>> from translucency.fit import fit_planar
    >>> from translucency.fit.held_out import held_out_error
    >>> ds = default_dataset()
    >>> e = held_out_error(fit_planar(ds, "iso", n_terms=2, max_rounds=1, half=0), ds)
    >>> 0 < e < 1
    True
    """
    sq_err, sq_data = held_out_terms(fit, ds, near=near, chunk_points=chunk_points)
    return float(np.sqrt(sq_err.sum() / max(sq_data.sum(), 1e-300)))


def held_out_terms(
    fit: FitResult, ds: PlanarDataset, *, near: float = 0.0, chunk_points: int = 32, variance: bool = False
):
    """Per incident point, ‖αP − y‖² and ‖y‖² over the held-out half of its pairs (planar), (P,) each;
    with ``variance``, also Σσ² over the same pairs (the data set's ``variance``, mm⁻⁴), the noise floor.

    α at a held-out pair's pixel comes from the windows where that pixel was
    fitted; pixels no fitted pair covers take the mean α of their fitted
    4-neighbours.  Pairs as in the fit (mask set, finite, flagged points left
    out: their terms are 0), from the smallest radius the fit saw in each window on:
    the halves interleave, so the first held-out ring may lie inside the first fitted one,
    and a profile is not asked to extrapolate towards x_i; and at least ``near`` mm from x_i.

    Examples
    --------
    >>> import numpy as np
    >>> from translucency.data import default_dataset
    >>> from translucency.fit import fit_planar
    >>> from translucency.fit.held_out import held_out_terms
    >>> ds = default_dataset()
    >>> fit = fit_planar(ds, "iso", n_terms=2, max_rounds=1, half=0)
    >>> sq_err, sq_data, sq_var = held_out_terms(fit, ds, variance=True)
    >>> sq_err.shape, sq_data.shape
    ((1024,), (1024,))
    >>> noise = np.sqrt(sq_var.sum() / sq_data.sum())   # what the true profile would score
    >>> bool(0 < noise < np.sqrt(sq_err.sum() / sq_data.sum()))
    True
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
    sq_err, sq_data, sq_var = np.zeros(ds.n_points), np.zeros(ds.n_points), np.zeros(ds.n_points)
    for s, e in chunks:
        y, r, theta, pixel, valid, train = pairs(s, e)
        var = ds.read("variance", s, e).astype(np.float64).reshape(y.shape) if variance else None
        # no inward extrapolation: held-out pairs from the smallest radius the fit saw in the window on
        r_fit = np.where(valid & train, r, np.inf).min(axis=1, keepdims=True)
        test = valid & ~train & (r >= np.maximum(r_fit, near))
        for k in range(e - s):  # one point at a time: its parameters broadcast over its pairs
            t = test[k]
            pred = alpha[pixel[k, t]][:, None] * model.profile(np.int64(s + k), r[k, t], theta[k, t])
            sq_err[s + k] = np.sum((pred - y[k, t]) ** 2)
            sq_data[s + k] = np.sum(y[k, t] ** 2)
            if variance:
                sq_var[s + k] = np.sum(var[k, t])
    return (sq_err, sq_data, sq_var) if variance else (sq_err, sq_data)


def mesh_held_out_terms(fit: FitResult, group, *, chunk_points: int = 32, variance: bool = False):
    """Per incident point, ‖αP − y‖² and ‖y‖² over the held-out half of its pairs (mesh), (P,) each; with
    ``variance``, also Σσ² over the same pairs and with the same weights (mm⁻⁴ mm²), the noise floor.

    A pair (i, v) is held out when :func:`vertex_half` differs from the fit's ``half``; pairs as the fit
    reads them (finite, at least the fit's exclusion radius from x_i, not flagged), each weighted by its
    vertex's area A_v (mm²), so that a finely meshed region does not count more than a coarse one.
    α at v was fitted from the other points' pairs on v (pooled over its disc).  σ² is the data set's
    ``R_d_var`` where it holds one (measured from photographs), else the simulated tally's
    :data:`~translucency.acquire.mesh.TALLY_VARIANCE_FACTOR` R_d / (N A_v); 0 where neither is known.

    Examples
    --------
    >>> import tempfile, trimesh
    >>> import translucency as tl
    >>> from translucency.fit.held_out import mesh_held_out_terms
    >>> from translucency.fit.mesh import fit_mesh
    >>> ball = trimesh.creation.icosphere(2, radius=4.0)
    >>> data = tl.acquire_mesh(ball, tempfile.mkdtemp() + "/ball.zarr", "homogeneous:marble", voxel_mm=1.0,
    ...                        points=4, photons=300, index_matched=True)
    >>> fit = fit_mesh(data.path, "iso", n_terms=1, max_rounds=1, half=0)
    >>> sq_err, sq_data = mesh_held_out_terms(fit, data.group)
    >>> sq_err.shape, bool((sq_data > 0).all())
    ((4,), True)
    """
    model, fitted = fit.model, int(fit.options["half"])
    vertices = np.asarray(group["vertices"][...], dtype=np.float64)
    area = np.asarray(group["vertex_area"][...], dtype=np.float64)
    alpha = np.asarray(model.alpha.values, dtype=np.float64)
    x_i = np.asarray(model.x_i, dtype=np.float64)
    P = len(x_i)
    sq_err, sq_data, sq_var = np.zeros(P), np.zeros(P), np.zeros(P)
    tally_scale = _tally_variance_scale(group, area) if variance and "R_d_var" not in group else None
    for s in range(0, P, chunk_points):
        e = min(s + chunk_points, P)
        y, r, valid = read_pairs(group, vertices, x_i, float(fit.options["exclusion_mm"]), s, e)
        if not variance:
            var = None
        elif tally_scale is None:
            var = np.asarray(group["R_d_var"][s:e], dtype=np.float64)
        else:
            var = y.astype(np.float64) * tally_scale[None, :, None]
        test = valid & (vertex_half(np.arange(s, e), np.arange(len(vertices))) != fitted)
        test &= ~fit.flagged[s:e, None]
        for k in range(e - s):  # one point at a time: its parameters broadcast over its (V, 3) pairs
            t = test[k]
            pred = alpha[t, None] * model.profile(np.int64(s + k), r[k, t], np.zeros(t.sum()))
            sq_err[s + k] = np.sum(area[t, None] * (pred - y[k, t]) ** 2)
            sq_data[s + k] = np.sum(area[t, None] * y[k, t].astype(np.float64) ** 2)
            if variance:
                sq_var[s + k] = np.sum(area[t, None] * var[k, t])
    return (sq_err, sq_data, sq_var) if variance else (sq_err, sq_data)


def _tally_variance_scale(group, area: np.ndarray) -> np.ndarray:
    """σ² / R_d per vertex (V,) of a simulated mesh data set, mm⁻²: the barycentric tally's
    :data:`~translucency.acquire.mesh.TALLY_VARIANCE_FACTOR` / (N A_v); 0 without a photon count."""
    from ..acquire.mesh import TALLY_VARIANCE_FACTOR  # the acquisition (trimesh, Mitsuba) loads only here

    photons = (group.attrs.get(MESH_HEADER_KEY) or {}).get("photons")
    if not photons:
        return np.zeros_like(area)
    return TALLY_VARIANCE_FACTOR / (float(photons) * np.maximum(area, 1e-12))
