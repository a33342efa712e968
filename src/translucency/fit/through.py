r"""The through-body table of a fitted per-vertex model (:mod:`translucency.model.through`).

For every incident point i and channel, over the cells of the grid in :math:`n_i \cdot n_o` and r,

.. math:: k_i = \frac{\sum_{j \in N(i)} \sum_{o \in \text{cell}} A_o\, R_d^{meas}(x_j, x_o)}
                     {\sum_{j \in N(i)} \sum_{o \in \text{cell}} A_o\, \alpha_o P_j(|x_o - x_j|)},

N(i) the ``pool`` incident points nearest i (i included): a ratio of sums, so that a cell holding a few
dim pairs of one point does not follow its photon noise; a cell without pairs keeps 1; k within
[1/8, 8] (``K_LIMIT``).  The value is the cell's, placed at its centre and interpolated between centres by
the renderer — so a pair's factor is its cell's only at the centre.  (Choosing the node values so that the
*interpolated* table carries every cell's energy exactly was tried: it oscillates between neighbouring
nodes, down to 0, wherever the data change steeply between cells.)  The pairs are those the fit reads
(:func:`translucency.fit.mesh_pairs.read_pairs`: r at least the exclusion radius, flagged pairs left out).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..model.through import COS_EDGES, K_LIMIT, R_EDGES, cells
from .mesh_pairs import exclusion_radius, mean_edge_length, read_pairs

#: incident points whose sums pool into each point's table
POOL = 8


def cell_energies(ds, model, *, exclusion: float | None = None, chunk_points: int = 16):
    r"""Measured and modelled energy, :math:`\sum A_o R_d`, per incident point, cell and channel: two
    (P, 4 · 8, 3) arrays (cells flat, cos-major)."""
    g = ds.group
    v = np.asarray(g["vertices"][...], dtype=np.float64)
    n = np.asarray(g["normals"][...], dtype=np.float64)
    area = np.asarray(g["vertex_area"][...], dtype=np.float64)
    incident = np.asarray(g["incident"][...])
    exclusion = exclusion_radius(mean_edge_length(v, np.asarray(g["faces"][...])), exclusion)
    P = len(incident)
    Br = len(R_EDGES) - 1
    Q = (len(COS_EDGES) - 1) * Br
    meas, mod = np.zeros((P, Q, 3)), np.zeros((P, Q, 3))
    x_i = v[incident]
    alpha_o = model.alpha.at(v)  # α per vertex (V,)
    for s in range(0, P, chunk_points):
        e = min(s + chunk_points, P)
        y, r, valid = read_pairs(g, v, x_i, exclusion, s, e)
        k = len(y)
        # the model at the same pairs, α and the colour scale included (as the evaluation reads it)
        i = np.broadcast_to(np.arange(s, e)[:, None], r.shape)
        R_model = model.R_d(i, np.broadcast_to(v, (k, len(v), 3)), alpha_o=np.broadcast_to(alpha_o, r.shape))
        ic, ir = cells(n[incident[s : s + k]] @ n.T, r)
        for j in range(k):
            ok = valid[j]
            cell = ic[j, ok] * Br + ir[j, ok]
            for ch in range(3):
                meas[s + j, :, ch] = np.bincount(cell, area[ok] * y[j, ok, ch], Q)
                mod[s + j, :, ch] = np.bincount(cell, area[ok] * R_model[j, ok, ch], Q)
    return meas, mod


def measure_through(ds, model, *, exclusion: float | None = None, pool: int = POOL, chunk_points: int = 16):
    """The table k (P, 4, 8, 3) of ``model`` (a fitted per-vertex exponential model) against the mesh data
    set ``ds`` it was fitted to (module docstring).

    Examples
    --------
    >>> import tempfile, trimesh
    >>> import translucency as tl
    >>> from translucency.fit.through import measure_through
    >>> ball = trimesh.creation.icosphere(2, radius=4.0)
    >>> data = tl.acquire_mesh(ball, tempfile.mkdtemp() + "/ball.zarr", "homogeneous:marble", voxel_mm=1.0,
    ...                        points=4, photons=300, index_matched=True)
    >>> fitting = tl.fit_model(data, "iso", n_terms=1, max_rounds=1)
    >>> measure_through(data, fitting.model).shape   # points, 4 normal cells, 8 distance cells, RGB
    (4, 4, 8, 3)
    """
    meas, mod = cell_energies(ds, model, exclusion=exclusion, chunk_points=chunk_points)
    P = len(meas)
    x_i = np.asarray(ds.group["vertices"][...], dtype=np.float64)[np.asarray(ds.group["incident"][...])]
    nearest = cKDTree(x_i).query(x_i, k=min(pool, P))[1].reshape(P, -1)
    meas_p, mod_p = meas[nearest].sum(axis=1), mod[nearest].sum(axis=1)
    table = np.divide(meas_p, mod_p, out=np.ones_like(meas_p), where=(mod_p > 0) & (meas_p > 0))
    return np.clip(table, 1.0 / K_LIMIT, K_LIMIT).reshape(P, len(COS_EDGES) - 1, len(R_EDGES) - 1, 3)
