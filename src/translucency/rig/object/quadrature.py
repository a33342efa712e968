r"""Cell means over a mesh: the quadrature of :math:`\int \phi_v f\, dA` over the cell of each vertex v
(:math:`\phi_v` its hat function), graded towards a point where f has a 1/r core (the laser's hit).

The near peak (:mod:`.near_peak`) and the shape's gains (:mod:`.shape_gain`) take their cell means of a
radial profile with it.  Units: mm, mm².
"""

from __future__ import annotations

import numpy as np

#: sub-triangles a face side of the cells' quadrature (n² centroids a face)
QUADRATURE_N = 6
#: halvings of the graded rule towards the hit
GRADED_LEVELS = 8


def subtriangle_centroids(n: int = QUADRATURE_N) -> np.ndarray:
    """Barycentric coordinates (n², 3) of the centroids of a triangle cut into n² equal sub-triangles: a
    rule of equal weights exact for linear functions.

    Examples
    --------
    >>> b = subtriangle_centroids(3)
    >>> b.shape, bool(np.allclose(b.sum(axis=1), 1)), np.round(b.mean(axis=0), 6).tolist()
    ((9, 3), True, [0.333333, 0.333333, 0.333333])
    """
    up = [((i + 1 / 3) / n, (j + 1 / 3) / n) for i in range(n) for j in range(n - i)]
    down = [((i + 2 / 3) / n, (j + 2 / 3) / n) for i in range(n - 1) for j in range(n - 1 - i)]
    ab = np.array(up + down)
    return np.column_stack([ab, 1.0 - ab.sum(axis=1)])


def graded_centroids(n: int = QUADRATURE_N, levels: int = GRADED_LEVELS):
    """Barycentric points (K, 3) and weights (K,) summing to 1 over a triangle, graded towards its first
    corner: the triangle is cut in four, the three children away from the corner take
    :func:`subtriangle_centroids`, the corner's child is cut again, ``levels`` times.  For a profile with a
    1/r core at that corner (the first scattering's) the plain rule misses part of the core's share.

    Examples
    --------
    ∫ 1/r over the unit right triangle with the corner at r = 0 is √2 ln(1 + √2); the rule's share of it,
    plain and graded three times:

    >>> exact = np.sqrt(2) * np.log(1 + np.sqrt(2))
    >>> for levels in (0, 3):
    ...     b, w = graded_centroids(4, levels)
    ...     share = float(w @ (1 / np.hypot(b[:, 1], b[:, 2]))) / 2 / exact
    ...     print(levels, round(share, 3), round(w.sum(), 6))
    0 0.965 1.0
    3 0.996 1.0
    """
    rule = subtriangle_centroids(n)
    corner = np.eye(3)
    points, weights, scale = [], [], 1.0
    for _ in range(levels):
        A, B, C = corner
        ab, ac, bc = (A + B) / 2, (A + C) / 2, (B + C) / 2
        for child in ((ab, B, bc), (ac, bc, C), (ab, bc, ac)):
            points.append(rule @ np.array(child))
            weights.append(np.full(len(rule), scale / 4 / len(rule)))
        corner, scale = np.array([A, ab, ac]), scale / 4
    points.append(rule @ corner)
    weights.append(np.full(len(rule), scale / len(rule)))
    return np.concatenate(points), np.concatenate(weights)


def cell_quadrature(mesh, vertices, n: int = QUADRATURE_N, toward=None):
    r"""Points and weights over the cells of ``vertices``: for a function f on the surface,
    :math:`\int \phi_v f\, dA \approx \sum_k w_k f(y_k)` over the points k of v, so Σ_k w_k = A_v.
    With ``toward`` (a point, mm), the faces with a corner there (within a thousandth of their longest
    edge) take the rule graded towards it (:func:`graded_centroids`): the hit's 1/r core.

    Returns ``points`` (K, 3) mm, ``weights`` (K,) mm² and ``owner`` (K,): the index into ``vertices``.

    Examples
    --------
    >>> import trimesh
    >>> from translucency.geometry import vertex_areas
    >>> mesh = trimesh.creation.icosphere(2, radius=3.0)
    >>> _, w, owner = cell_quadrature(mesh, [0, 5])
    >>> bool(np.allclose(np.bincount(owner, weights=w), vertex_areas(mesh)[[0, 5]]))
    True
    """
    bary = subtriangle_centroids(n)
    graded, graded_w = graded_centroids(n) if toward is not None else (None, None)
    faces = np.asarray(mesh.faces)
    verts = np.asarray(mesh.vertices, dtype=np.float64)
    face_area = np.asarray(mesh.area_faces, dtype=np.float64)
    points, weights, owner = [], [], []
    vertex_faces = mesh.vertex_faces
    for k, v in enumerate(np.asarray(vertices, dtype=np.int64)):
        fs = vertex_faces[v]
        fs = fs[fs >= 0]
        tri = faces[fs]  # (F, 3)
        corner = np.argmax(tri == v, axis=1)  # where v sits in each face
        P = np.einsum("kc,fcd->fkd", bary, verts[tri])  # (F, n², 3)
        phi = bary[:, corner].T  # (F, n²): v's barycentric coordinate at each point
        keep = np.ones(len(fs), dtype=bool)
        if toward is not None:  # faces with a corner at the hit: the graded rule, rolled to that corner
            dist = np.linalg.norm(verts[tri] - np.asarray(toward), axis=2)  # (F, 3)
            edge = np.linalg.norm(verts[tri] - verts[np.roll(tri, 1, axis=1)], axis=2).max(axis=1)
            at = np.argmin(dist, axis=1)
            keep = dist[np.arange(len(fs)), at] > 1e-3 * edge
            for f in np.flatnonzero(~keep):
                b = np.roll(graded, at[f], axis=1)  # the graded corner moved to corner `at`
                points.append(b @ verts[tri[f]])
                weights.append(b[:, corner[f]] * graded_w * face_area[fs[f]])
                owner.append(np.full(len(b), k))
        points.append(P[keep].reshape(-1, 3))
        weights.append((phi[keep] * face_area[fs[keep], None] / len(bary)).ravel())
        owner.append(np.full(int(keep.sum()) * len(bary), k))
    return np.concatenate(points), np.concatenate(weights), np.concatenate(owner)
