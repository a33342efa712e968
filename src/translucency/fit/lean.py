r"""Fit the lean (:mod:`translucency.model.lean`) from a mesh data set's oblique beams.

At incident point i, each oblique beam d (``acquire mesh --incidence``) measured :math:`R_{d,d}(x_i, v)`
beside the normal beam's :math:`R_{d,0}(x_i, v)`.  The lean predicts, per channel,

.. math:: \hat R_{d}(v) = s_d\, R_{d,0}(v)\, \frac{e^{g_d(v)}}{Z_d}, \qquad
          g_d(v) = \kappa\, \vec\ell_d \cdot \hat d_v - \lambda\, (\vec\ell_d \cdot n_i)\, r_v, \qquad
          Z_d = \frac{\sum_v A_v R_{d,0}(v)\, e^{g_d(v)}}{\sum_v A_v R_{d,0}(v)},

with :math:`s_d` the beam's measured total over the normal one's (the incidence law's business, not the
lean's) and :math:`\vec\ell_d` the beam's lean vector.  Three steps per point and channel, each a grid
search (the power per vertex :math:`A_v R` weighs the pairs; the point's own vertex is left out: no
direction there):

1. κ ∈ [0, ``KAPPA_MAX``] with λ = 0, minimising :math:`\sum_{d, v} A_v^2 (R_{d}(v) - \hat R_d(v))^2` — the
   lobe's direction, which the near pairs carry;
2. λ ∈ [0, ``LAMBDA_MAX``] matching the beams' mean distance :math:`\sum_v A_v R\, r_v / \sum_v A_v R` — the
   reach, which the squared error hardly sees (the far pairs carry little power each, but the light a
   back-lit object shows);
3. κ again with that λ.

The grid's best node is refined by a parabola through it and its neighbours.
"""

from __future__ import annotations

import numpy as np

from .._validate import TranslucencyError
from ..model.lean import KAPPA_MAX, LAMBDA_MAX, lean_vector

#: the κ grid of the search (the parabola refines between its nodes)
_GRID = np.linspace(0.0, KAPPA_MAX, 33)
#: the λ grid, mm⁻¹
_LAMBDAS = np.linspace(0.0, LAMBDA_MAX, 41)


def lean_loss(R0, R1, area, a, depth=None) -> np.ndarray:
    """The fit's loss per κ node, (G, C): ``R0`` (V, C) the normal beam, ``R1`` (D, V, C) the oblique
    ones, ``area`` (V,), ``a`` (D, V) the lean vector dotted with the pair's direction (0 where unused),
    ``depth`` (D, V, C) the reach term λ (ℓ · n) r already multiplied out (None: 0)."""
    M0 = area[:, None] * R0  # (V, C) power per vertex
    M1 = area[None, :, None] * R1  # (D, V, C)
    s = M1.sum(axis=1) / np.maximum(M0.sum(axis=0), 1e-30)  # (D, C)
    reach = 1.0 if depth is None else np.exp(-depth)
    loss = np.empty((len(_GRID), R0.shape[1]))
    for g, kappa in enumerate(_GRID):
        shaped = M0[None] * np.exp(kappa * a)[..., None] * reach  # (D, V, C)
        Z = shaped.sum(axis=1) / np.maximum(M0.sum(axis=0), 1e-30)  # (D, C)
        model = s[:, None, :] * shaped / np.maximum(Z, 1e-30)[:, None, :]
        loss[g] = ((M1 - model) ** 2).sum(axis=(0, 1))
    return loss


def reach_loss(R0, R1, area, a, ln, r, kappa) -> np.ndarray:
    """The squared mismatch of the beams' mean distance per λ node, (L, C): ``ln`` (D,) each beam's ℓ · n,
    ``r`` (V,) the distances (mm), ``kappa`` (C,) the lobe's."""
    M0 = area[:, None] * R0
    M1 = area[None, :, None] * R1
    measured = (M1 * r[None, :, None]).sum(axis=1) / np.maximum(M1.sum(axis=1), 1e-30)  # (D, C)
    out = np.empty((len(_LAMBDAS), R0.shape[1]))
    for k, lam in enumerate(_LAMBDAS):
        g = a[..., None] * kappa[None, None, :] - lam * (ln[:, None] * r[None, :])[..., None]
        shaped = M0[None] * np.exp(g)  # (D, V, C)
        predicted = (shaped * r[None, :, None]).sum(axis=1) / np.maximum(shaped.sum(axis=1), 1e-30)
        out[k] = ((predicted - measured) ** 2).sum(axis=0)
    return out


def _refine(loss: np.ndarray, grid: np.ndarray = _GRID) -> np.ndarray:
    """The parameter (C,) at the minimum of each channel's loss over ``grid``: the best node, moved to the
    vertex of the parabola through it and its two neighbours."""
    best = np.argmin(loss, axis=0)
    h = grid[1] - grid[0]
    out = grid[best].copy()
    for c, b in enumerate(best):
        if 0 < b < len(grid) - 1:
            y0, y1, y2 = loss[b - 1, c], loss[b, c], loss[b + 1, c]
            den = y0 - 2 * y1 + y2
            if den > 0:
                out[c] += 0.5 * h * (y0 - y2) / den
    return np.clip(out, grid[0], grid[-1])


def fit_point(R0, R1, area, a, ln, r) -> np.ndarray:
    """(κ, λ) per channel, (2, C), of one incident point: the three steps of the module docstring
    (``a`` (D, V) ℓ · d̂, ``ln`` (D,) ℓ · n, ``r`` (V,) mm)."""
    kappa = _refine(lean_loss(R0, R1, area, a))
    lam = _refine(reach_loss(R0, R1, area, a, ln, r, kappa), _LAMBDAS)
    depth = lam[None, None, :] * (ln[:, None] * r[None, :])[..., None]
    kappa = _refine(lean_loss(R0, R1, area, a, depth))
    return np.stack([kappa, lam])


def fit_lean(ds, chunk_points: int = 32, progress=None) -> np.ndarray:
    """κ and λ per incident point and channel, (P, 2, 3), from a mesh data set with oblique beams.

    Parameters
    ----------
    ds : MeshDataset
        With ``ds.incidence`` holding oblique directions (``acquire mesh --incidence``).
    chunk_points : int
        Points read at once.

    Returns
    -------
    ndarray, shape (P, 2, 3)
        ``[:, 0]`` κ ≥ 0, ``[:, 1]`` λ ≥ 0 in mm⁻¹.

    Examples
    --------
    A ball scanned with beams at 45° besides the normal ones (two azimuths):

    >>> import tempfile, trimesh
    >>> import translucency as tl
    >>> from translucency.fit.lean import fit_lean
    >>> ball = trimesh.creation.icosphere(2, radius=4.0)
    >>> data = tl.acquire_mesh(ball, tempfile.mkdtemp() + "/ball.zarr", "homogeneous:marble", voxel_mm=1.0,
    ...                        points=4, photons=300, index_matched=True, incidence=(45,), azimuths=2)
    >>> lean = fit_lean(data)
    >>> lean.shape, bool((lean >= 0).all())
    ((4, 2, 3), True)
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
    lean = np.zeros((P, 2, 3))
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
            ln = ell @ frames[p, 2]  # (D,): 1 − cos θ_t
            lean[p] = fit_point(R0[k] * use[:, None], R1[k] * use[None, :, None], area, a, ln, r)
        if progress is not None:
            progress(e - s)
    return lean
