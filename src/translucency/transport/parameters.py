r"""Per-vertex parameters: every vertex's profile, blended from the fitted incident points nearest it along
the surface.

The fit gives parameters at the incident points only.  Vertex v gets the profile
:math:`P_v(r) = \sum_j w_{vj} P_j(r)` of its k nearest incident points j, inverse-square-distance
weights :math:`w_{vj}` over distances along the surface (:func:`geodesic_neighbours`, Dijkstra over the
mesh's edges, mm) — the amplitudes c (mm⁻²) and rates d (mm⁻¹, negative) of
:math:`P(r) = \sum_n c_n e^{d_n r}` per channel, and the colour scale (:func:`vertex_parameters`); and,
for a model that carries what its acquisition measured, each vertex's own-area value (mm⁻²) and total
exitance (dimensionless) (:func:`measured_per_vertex`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from .._validate import TranslucencyError


def geodesic_neighbours(mesh, sources: np.ndarray, k: int, limit: float | None = None):
    """The k incident vertices nearest to every vertex along the surface.

    Distances are shortest paths over the mesh's edges (Dijkstra, from all
    sources in chunks, up to ``limit`` mm — default three spacings of the
    sources); a vertex reaches fewer than k sources where the others are
    farther or on another piece of the mesh (their distance is inf).

    Returns
    -------
    dist, idx : ndarray, shape (V, k)
        Graph distances (mm, ascending) and indices into ``sources``.
    """
    V, P = len(mesh.vertices), len(sources)
    e = np.asarray(mesh.edges_unique)
    graph = sp.csr_matrix(
        (np.asarray(mesh.edges_unique_length, dtype=np.float64), (e[:, 0], e[:, 1])), shape=(V, V)
    )
    if limit is None:
        limit = 3.0 * np.sqrt(float(mesh.area) / max(P, 1))
    best_d, best_i = np.full((V, k), np.inf), np.zeros((V, k), dtype=np.int64)
    for s in range(0, P, 64):
        D = dijkstra(graph, directed=False, indices=sources[s : s + 64], limit=limit)  # (chunk, V)
        cand_d = np.concatenate([best_d, D.T], axis=1)
        cand_i = np.concatenate([best_i, np.broadcast_to(np.arange(s, s + len(D)), (V, len(D)))], axis=1)
        keep = np.argsort(cand_d, axis=1, kind="stable")[:, :k]
        best_d, best_i = np.take_along_axis(cand_d, keep, 1), np.take_along_axis(cand_i, keep, 1)
    return best_d, best_i


def neighbour_weights(model, vertices, k: int = 4):
    r"""Blend weights of the k incident points nearest each vertex: (w, idx), each (V, k).

    Inverse-square-distance weights :math:`w_j`, normalised, exact (a single 1) at an incident point.
    ``vertices``: positions (V, 3) — nearest in a straight line — or a mesh whose vertices the incident
    points are — nearest along the surface (:func:`geodesic_neighbours`), so that nothing leaks across a
    thin gap between two parts of an object; vertices that reach no incident point that way fall back to
    straight-line distances.
    """
    k = min(k, model.n_points)
    mesh = vertices if hasattr(vertices, "edges_unique") else None
    vertices = np.asarray(mesh.vertices if mesh is not None else vertices, dtype=np.float64)
    dist, idx = cKDTree(model.x_i).query(vertices, k=k)
    dist, idx = dist.reshape(len(vertices), k), idx.reshape(len(vertices), k)
    if mesh is not None:
        gap, src = cKDTree(np.asarray(mesh.vertices)).query(model.x_i)
        if np.all(gap <= 1e-6 * float(np.max(mesh.extents))):  # the incident points are vertices
            g_dist, g_idx = geodesic_neighbours(mesh, src, k)
            reached = np.isfinite(g_dist[:, 0])
            dist[reached], idx[reached] = g_dist[reached], g_idx[reached]
    w = 1.0 / np.maximum(dist, 1e-9) ** 2
    exact = dist[:, 0] < 1e-9
    w[exact] = 0.0
    w[exact, 0] = 1.0
    return w / w.sum(1, keepdims=True), idx


def vertex_parameters(model, vertices, k: int = 4, weights=None):
    r"""Each vertex's profile as a blend of the k nearest incident points' profiles.

    :math:`P_v(r) = \sum_j w_j P_j(r)` with the weights of :func:`neighbour_weights`
    (or ``weights`` = (w, idx) computed before), itself a sum of k·n exponentials —
    so c, d of shape (V, C, k·n) are returned (with the colour scale (V, 3)).
    Blending the profiles, not their parameters: the average of two exponentials'
    rates and amplitudes is a third exponential unlike either.
    """
    if model.kind != "exponential" or model.n_directions != 1:
        raise TranslucencyError(
            "model: rendering needs an isotropic exponential model (fit with --model iso)"
        )
    w, idx = neighbour_weights(model, vertices, k) if weights is None else weights
    V, k = w.shape
    C, n = model.c.shape[1], model.n_terms
    c = (w[:, :, None, None] * model.c[idx][:, :, :, 0]).transpose(0, 2, 1, 3).reshape(V, C, k * n)
    d = model.d[idx][:, :, :, 0].transpose(0, 2, 1, 3).reshape(V, C, k * n)
    if C == 1:  # shared colour: blend the scales with the same weights (exact where one point dominates)
        s = np.einsum("vk,vkc->vc", w, model.colour_scale[idx])
    else:
        s = np.ones((V, 3))
    return c, d, s


def measured_per_vertex(model, weights, vertices, area):
    r"""``model.measured``'s own and total (V, 3) at every vertex; (None, None) for a model without them.

    The total exitance blends with the profile weights.  The own-area value does not: R_d(x_i, x_i) is the
    mean over the incident vertex's own cell, so it grows as the cell shrinks toward the peak, and blending
    it across cells of other sizes misplaces energy.  What blends is the fraction of the total that stays
    in the own cell, :math:`f_i = A_i\,\mathrm{own}_i / \mathrm{total}_i` (A_i: the area of the vertex
    nearest x_i):

    .. math:: \mathrm{total}_v = \sum_j w_{vj}\,\mathrm{total}_j, \qquad
              \mathrm{own}_v = \frac{\mathrm{total}_v}{A_v} \sum_j w_{vj}\, f_j

    (how much each choice errs against a converged reference: docs/near-field.md).
    """
    if not model.measured or not {"own", "total"} <= set(model.measured):
        return None, None
    w, idx = weights
    own_i, total_i = model.measured["own"], model.measured["total"]  # (P, 3): mm⁻², 1
    A_i = area[cKDTree(vertices).query(model.x_i)[1]]  # the incident points' own cells, mm²
    f_i = np.divide(A_i[:, None] * own_i, total_i, out=np.zeros_like(own_i), where=total_i > 0)
    total = np.einsum("vk,vkc->vc", w, total_i[idx])
    own = np.einsum("vk,vkc->vc", w, np.clip(f_i, 0.0, 1.0)[idx]) * total / area[:, None]
    return own, total
