r"""Exitance between the vertices without the triangles showing: limited linear reconstructions per vertex.

Linear interpolation of per-vertex exitance over a coarse mesh shows its triangles (the value's slope
jumps at every edge: Mach bands).  Each vertex v gets instead a gradient :math:`G_v` of M along its
tangent plane, by least squares over its one-ring,

.. math:: G_v = \arg\min_G \sum_{n \in N(v)} \bigl(M_n - M_v - G \cdot (x_n - x_v)\bigr)^2
          + \lambda\, (G \cdot n_v)^2,

and a point x of the triangle (v_0, v_1, v_2) at barycentrics b takes the blend of the three vertices'
first-order reconstructions

.. math:: M(x) = \sum_j b_j \bigl(M_{v_j} + \phi_{v_j}\, G_{v_j} \cdot (x - x_{v_j})\bigr),

exact for a linear field, continuous across edges (on an edge only its two vertices' reconstructions
enter), and curved inside each triangle.  :math:`\phi_v \in [0, 1]` is Barth and Jespersen's limiter
(1989): the largest factor for which the reconstruction at every neighbour stays within the one-ring's
values, so the blend adds no new extremum (no overshoot, no negative exitance at a shadow edge).
"""

from __future__ import annotations

import numpy as np


class OneRing:
    """Each vertex's one-ring, and the least-squares system of its gradient, prepared once per mesh;
    :meth:`gradients` then costs a few sums per exitance."""

    def __init__(self, vertices, faces, normals):
        v = np.asarray(vertices, np.float64)
        n = np.asarray(normals, np.float64)
        V = len(v)
        e = np.asarray(faces, np.int64)[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
        e = np.unique(np.sort(e, axis=1), axis=0)
        # both directions of every edge, grouped by their first vertex (segments for the reductions)
        a, b = np.concatenate([e[:, 0], e[:, 1]]), np.concatenate([e[:, 1], e[:, 0]])
        order = np.argsort(a, kind="stable")
        self.a, self.b = a[order], b[order]
        self.starts = np.flatnonzero(np.r_[True, self.a[1:] != self.a[:-1]])
        self.owners = self.a[self.starts]
        self.V = V
        self.d = v[self.b] - v[self.a]  # (E, 3)
        # normal equations per vertex, the normal direction held at 0 by λ n nᵀ
        d = self.d
        A = np.stack(
            [np.bincount(self.a, weights=d[:, i] * d[:, j], minlength=V) for i in range(3) for j in range(3)],
            axis=1,
        ).reshape(V, 3, 3)
        lam = np.trace(A, axis1=1, axis2=2) / np.maximum(np.bincount(self.a, minlength=V), 1)
        A += lam[:, None, None] * n[:, :, None] * n[:, None, :] + 1e-12 * np.eye(3)
        self.A_inv = np.linalg.inv(A)

    def gradients(self, M) -> np.ndarray:
        """(V, C, 3) limited gradients of the per-vertex field M (V, C) (module docstring)."""
        M = np.asarray(M, np.float64)
        a, b, d, starts, owners = self.a, self.b, self.d, self.starts, self.owners
        C = M.shape[1]
        dM = M[b] - M[a]  # (E, C)
        B = np.stack(
            [
                np.bincount(a, weights=d[:, i] * dM[:, c], minlength=self.V)
                for i in range(3)
                for c in range(C)
            ],
            axis=1,
        ).reshape(self.V, 3, C)
        G = np.einsum("vij,vjc->vci", self.A_inv, B)  # (V, C, 3)
        # Barth–Jespersen: reconstructions at the one-ring's vertices stay within the one-ring's range
        hi, lo = M.copy(), M.copy()
        hi[owners] = np.maximum(hi[owners], np.maximum.reduceat(M[b], starts, axis=0))
        lo[owners] = np.minimum(lo[owners], np.minimum.reduceat(M[b], starts, axis=0))
        hi, lo = hi - M, lo - M  # allowed change, ≥ 0 and ≤ 0
        step = np.einsum("ecx,ex->ec", G[a], d)  # the reconstruction's change at each neighbour
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(step > 0, hi[a] / step, np.where(step < 0, lo[a] / step, np.inf))
        phi = np.ones(M.shape)
        phi[owners] = np.minimum.reduceat(np.clip(ratio, 0.0, 1.0), starts, axis=0)
        return G * phi[:, :, None]


def limited_gradients(vertices, faces, normals, M) -> np.ndarray:
    """Per-vertex limited gradients (V, 3 channels, 3) of the exitance M (V, 3) (module docstring);
    :class:`OneRing` prepares the mesh once for many exitances.

    Examples
    --------
    >>> import trimesh
    >>> plane = trimesh.creation.box((10, 10, 1e-3))  # a linear field on a flat face is reproduced
    >>> v, f = plane.vertices, plane.faces
    >>> M = np.repeat((2.0 + 0.1 * v[:, :1]), 3, axis=1)
    >>> G = limited_gradients(v, f, plane.vertex_normals, M)
    >>> bool(np.all(np.abs(G[..., 2]) < 1e-6))
    True
    """
    return OneRing(vertices, faces, normals).gradients(M)
