r"""Fit the lean (:mod:`translucency.model.lean`) from a mesh data set's oblique beams.

At incident point i, each oblique beam d (``acquire mesh --incidence``) measured :math:`R_{d,d}(x_i, v)`
beside the normal beam's :math:`R_{d,0}(x_i, v)`.  The lean predicts, per channel,

.. math:: \hat R_{d}(v) = s_d\, R_{d,0}(v)\, \frac{e^{\kappa\, \vec\ell_d \cdot \hat d_v}}{Z_d(\kappa)},
          \qquad Z_d = \frac{\sum_v A_v R_{d,0}(v)\, e^{\kappa \vec\ell_d \cdot \hat d_v}}
                            {\sum_v A_v R_{d,0}(v)},

with :math:`s_d` the beam's measured total over the normal one's (the incidence law's business, not the
lean's) and :math:`\vec\ell_d` the beam's lean vector.  κ ∈ [0, ``KAPPA_MAX``] minimises the squared error
of the power per vertex, :math:`\sum_{d, v} A_v^2 (R_{d}(v) - \hat R_d(v))^2`, over all beams of the
point (its own vertex left out: no direction there) — a grid, then a parabola through the best three.
"""

from __future__ import annotations

import numpy as np

from .._validate import TranslucencyError
from ..model.lean import KAPPA_MAX, lean_vector

#: the κ grid of the search (the parabola refines between its nodes)
_GRID = np.linspace(0.0, KAPPA_MAX, 33)


def lean_loss(R0, R1, area, a) -> np.ndarray:
    """The fit's loss per grid node, (G, C): ``R0`` (V, C) the normal beam, ``R1`` (D, V, C) the oblique
    ones, ``area`` (V,), ``a`` (D, V) the lean vector dotted with the pair's direction (0 where unused)."""
    M0 = area[:, None] * R0  # (V, C) power per vertex
    M1 = area[None, :, None] * R1  # (D, V, C)
    s = M1.sum(axis=1) / np.maximum(M0.sum(axis=0), 1e-30)  # (D, C)
    loss = np.empty((len(_GRID), R0.shape[1]))
    for g, kappa in enumerate(_GRID):
        lobe = np.exp(kappa * a)[..., None]  # (D, V, 1)
        shaped = M0[None] * lobe  # (D, V, C)
        Z = shaped.sum(axis=1) / np.maximum(M0.sum(axis=0), 1e-30)  # (D, C)
        model = s[:, None, :] * shaped / np.maximum(Z, 1e-30)[:, None, :]
        loss[g] = ((M1 - model) ** 2).sum(axis=(0, 1))
    return loss


def _refine(loss: np.ndarray) -> np.ndarray:
    """κ (C,) at the minimum of each channel's loss over the grid: the best node, moved to the vertex of
    the parabola through it and its two neighbours."""
    best = np.argmin(loss, axis=0)
    h = _GRID[1] - _GRID[0]
    out = _GRID[best].copy()
    for c, b in enumerate(best):
        if 0 < b < len(_GRID) - 1:
            y0, y1, y2 = loss[b - 1, c], loss[b, c], loss[b + 1, c]
            den = y0 - 2 * y1 + y2
            if den > 0:
                out[c] += 0.5 * h * (y0 - y2) / den
    return np.clip(out, 0.0, KAPPA_MAX)


def fit_lean(ds, chunk_points: int = 32, progress=None) -> np.ndarray:
    """κ per incident point and channel, (P, 3), from a mesh data set with oblique beams.

    Parameters
    ----------
    ds : MeshDataset
        With ``ds.incidence`` holding oblique directions (``acquire mesh --incidence``).
    chunk_points : int
        Points read at once.

    Returns
    -------
    ndarray, shape (P, 3)
        κ ≥ 0.

    Examples
    --------
    >>> kappa = fit_lean(open_mesh_dataset("spot_angles.zarr"))  # doctest: +SKIP
    """
    inc = ds.incidence
    if inc.count == 1:
        raise TranslucencyError(f"{ds.path}: no oblique beams to fit the lean from (acquire --incidence)")
    eta = 1.0 if ds.header.get("request", {}).get("index_matched") else float(ds.header["eta"])
    vertices = np.asarray(ds.group["vertices"][...], dtype=np.float64)
    area = np.asarray(ds.group["vertex_area"][...], dtype=np.float64)
    incident = np.asarray(ds.group["incident"][...])
    frames = ds.incident_frames()
    w = inc.world(frames)[:, 1:]  # (P, D, 3) toward the light, the oblique beams
    P = len(incident)
    kappa = np.zeros((P, 3))
    for s in range(0, P, chunk_points):
        e = min(s + chunk_points, P)
        R0 = np.asarray(ds.group["R_d"][s:e], dtype=np.float64)  # (k, V, 3)
        R1 = np.asarray(ds.group["R_d_oblique"][s:e], dtype=np.float64)  # (k, D, V, 3)
        for k in range(e - s):
            p = s + k
            d = vertices - vertices[incident[p]]
            r = np.linalg.norm(d, axis=1)
            use = r > 0
            d_hat = np.divide(d, r[:, None], out=np.zeros_like(d), where=use[:, None])
            ell = lean_vector(w[p], frames[p, 2][None, :], eta)  # (D, 3)
            a = ell @ d_hat.T  # (D, V); 0 at the own vertex
            R0_p, R1_p = R0[k] * use[:, None], R1[k] * use[None, :, None]
            kappa[p] = _refine(lean_loss(R0_p, R1_p, area, a))
        if progress is not None:
            progress(e - s)
    return kappa
