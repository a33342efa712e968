r"""The irradiance on a reduced set of vertices, with shadow edges kept at full resolution.

The path-traced irradiance is the cost of a new light (:mod:`translucency.scene.irradiance`), and most of
it is smooth across a few edges: it is traced at one vertex per cell of a grid ``spacing`` mean edges
wide (the vertex nearest the cell's centre of mass), and every other vertex v takes the mean of its
``k`` nearest traced vertices :math:`s` that face its way (:math:`n_v \cdot n_s > 0`), weighted by
inverse distance:

.. math:: \tilde E_v = \sum_s w_{vs} E_s, \qquad w_{vs} \propto \frac{1}{|x_v - x_s| + h/2},
          \quad \sum_s w_{vs} = 1.

Where those neighbours disagree — a shadow's edge, the rim of a lit patch — the interpolation would
blur what the light draws sharply; there the vertex is traced itself.  A vertex is *refined* where the
grey irradiance of its neighbours spans more than ``EDGE_CONTRAST`` of their largest,

.. math:: \max_s \bar E_s - \min_s \bar E_s > c\, \max_s \bar E_s ,

which a penumbra crosses and the estimate's own noise (a few per cent at 16 samples) does not.  Which
vertices are refined depends on the light; the cells and weights are built once per object.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

#: a vertex is traced itself where its neighbours' irradiance spans more than this share of their largest
EDGE_CONTRAST = 0.5
#: traced neighbours each vertex takes its irradiance from
NEIGHBOURS = 4


class ReducedVertices:
    """A mesh's vertices, one in every grid cell ``spacing`` mean edges wide traced (module docstring).

    Parameters
    ----------
    vertices, normals : ndarray, shape (V, 3)
        Positions (any length unit) and unit outward normals.
    mean_edge : float
        The mesh's mean edge length, in the positions' unit.
    spacing : float
        Cell width in mean edges (≥ 1; about ``spacing²`` vertices a cell on a surface).

    Examples
    --------
    >>> import trimesh
    >>> ball = trimesh.creation.icosphere(4)
    >>> reduced = ReducedVertices(ball.vertices, ball.vertex_normals, ball.edges_unique_length.mean(), 2.0)
    >>> 3 < len(ball.vertices) / len(reduced.traced) < 6
    True
    >>> E_s = np.ones((len(reduced.traced), 3))
    >>> bool(np.allclose(reduced.interpolate(E_s), 1.0))  # the weights sum to one
    True
    """

    def __init__(self, vertices: np.ndarray, normals: np.ndarray, mean_edge: float, spacing: float):
        x = np.asarray(vertices, np.float64)
        n = np.asarray(normals, np.float64)
        V = len(x)
        h = float(spacing) * float(mean_edge)
        # one vertex per occupied cell: the one nearest the cell's centre of mass
        cell = np.floor((x - x.min(axis=0)) / h).astype(np.int64)
        _, which = np.unique(cell, axis=0, return_inverse=True)
        which = which.ravel()
        count = np.bincount(which)
        centre = np.stack([np.bincount(which, x[:, k]) for k in range(3)], axis=1) / count[:, None]
        gap = np.linalg.norm(x - centre[which], axis=1)
        order = np.lexsort((gap, which))  # by cell, nearest first
        first = np.ones(V, bool)
        first[1:] = which[order][1:] != which[order][:-1]
        self.traced = np.sort(order[first])  # (S,) the traced vertices' indices
        # every vertex's nearest traced vertices that face its way, inverse-distance weights
        k = min(NEIGHBOURS, len(self.traced))
        dist, near = cKDTree(x[self.traced]).query(x, k=2 * k)
        dist, near = np.atleast_2d(dist.T).T, np.atleast_2d(near.T).T
        facing = np.einsum("vk,vjk->vj", n, n[self.traced[near]]) > 0
        facing[:, 0] |= ~facing.any(axis=1)  # none facing: the nearest
        rank = np.cumsum(facing, axis=1)
        keep = facing & (rank <= k)
        w = np.where(keep, 1.0 / (dist + 0.5 * h), 0.0)
        w /= w.sum(axis=1, keepdims=True)
        rows = np.repeat(np.arange(V), near.shape[1])
        self._W = sp.csr_matrix((w.ravel(), (rows, near.ravel())), shape=(V, len(self.traced)))
        self._W.eliminate_zeros()
        self.neighbours = np.where(keep, near, -1)  # (V, 2k) the traced neighbours (-1: none)

    def interpolate(self, values: np.ndarray) -> np.ndarray:
        """(V, c) every vertex's weighted mean of its traced neighbours' ``values`` (S, c)."""
        return np.asarray(self._W @ np.asarray(values, np.float64))

    def to_refine(self, E: np.ndarray) -> np.ndarray:
        """Indices of the vertices not traced whose traced neighbours' grey irradiance (``E`` (S, 3) at
        :attr:`traced`) spans more than :data:`EDGE_CONTRAST` of their largest (module docstring)."""
        grey = np.append(np.asarray(E, np.float64).mean(axis=1), np.nan)  # index -1: no neighbour
        g = grey[self.neighbours]
        hi, lo = np.nanmax(g, axis=1), np.nanmin(g, axis=1)
        edge = (hi - lo) > EDGE_CONTRAST * hi
        edge[self.traced] = False
        return np.flatnonzero(edge)
