r"""α's statistics pooled over a disc of vertices: :math:`(\mathcal{P} s)_v = \sum_{|x_u - x_v| \le h} s_u`.

The pool is a sparse V × V matrix of every pair within h — about :math:`V \cdot \pi h^2 / \bar A` entries
(Ā the mean cell area).  On a scan finer than the disc that grows as V²: 338 k vertices at h = 4.3 mm
would hold 7·10⁸ pairs (24 GB; the machine's whole memory).  Beyond :data:`MAX_ENTRIES` the disc is taken
through cells instead: the vertices are binned on a grid of side h / :data:`CELLS_PER_RADIUS`, each cell's
statistics summed, and each vertex pools the cells whose centroids lie within h,

.. math:: (\mathcal{P} s)_v \approx \sum_{c:\, |\bar x_c - x_v| \le h} \sum_{u \in c} s_u,

— the same disc to within a cell at its rim, with V · (a few dozen) entries whatever the scan's resolution.

Units: mm.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

#: the most entries the exact pool may hold (~0.5 GB as the CSR matrix and its construction)
MAX_ENTRIES = 2.5e7
#: grid cells across the disc's radius where the pool goes through cells
CELLS_PER_RADIUS = 4
#: vertices sampled to estimate the exact pool's size
SAMPLE = 2000


class VertexDiscPool:
    """The disc pool of the module docstring over ``vertices`` (V, 3) mm, radius ``radius`` mm; called on
    statistics (V,) or (V, k).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> v = rng.uniform(0, 10, (500, 3))
    >>> exact = VertexDiscPool(v, 2.0)
    >>> cells = VertexDiscPool(v, 2.0, max_entries=0)  # through cells
    >>> exact.cells, cells.cells
    (False, True)
    >>> s = np.ones(500)
    >>> bool(abs(np.median(cells(s) / exact(s)) - 1) < 0.1)  # about the same neighbours
    True
    """

    def __init__(self, vertices, radius: float, *, max_entries: float = MAX_ENTRIES):
        v = np.asarray(vertices, dtype=np.float64)
        n = len(v)
        tree = cKDTree(v)
        sample = v[np.linspace(0, n - 1, min(n, SAMPLE)).astype(np.int64)]
        per_vertex = float(np.mean(tree.query_ball_point(sample, radius, return_length=True)))
        self.cells = per_vertex * n > max_entries
        if not self.cells:  # every pair within the radius, both ways, and each vertex itself
            pairs = tree.query_pairs(radius, output_type="ndarray") if radius > 0 else np.zeros((0, 2), int)
            ij = np.concatenate([pairs, pairs[:, ::-1], np.repeat(np.arange(n)[:, None], 2, 1)])
            self.matrix = sp.csr_matrix((np.ones(len(ij)), (ij[:, 0], ij[:, 1])), shape=(n, n))
            return
        # the vertices binned on a grid of side h / CELLS_PER_RADIUS: S (cells × V) sums a cell's members
        side = radius / CELLS_PER_RADIUS
        key = np.floor((v - v.min(axis=0)) / side).astype(np.int64)
        _, cell = np.unique(key, axis=0, return_inverse=True)
        cell = cell.ravel()
        C = int(cell.max()) + 1
        S = sp.csr_matrix((np.ones(n), (cell, np.arange(n))), shape=(C, n))
        centroid = (S @ v) / np.asarray(S.sum(axis=1))
        # each vertex and the cells whose centroids lie within the radius (its own always among them)
        near = tree.sparse_distance_matrix(cKDTree(centroid), radius, output_type="ndarray")
        rows = np.concatenate([near["i"], np.arange(n)])
        cols = np.concatenate([near["j"], cell])
        M = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, C))
        M.data[:] = 1.0  # (duplicates summed on conversion: a vertex's own cell counted once)
        self.matrix = None  # (M S is never formed: it would hold the whole disc again)
        self._M, self._S = M, S

    def __call__(self, stat: np.ndarray) -> np.ndarray:
        if not self.cells:
            return self.matrix @ stat
        return self._M @ (self._S @ stat)


#: pools built lately, by (vertices' digest, radius): the candidate fits of a structure choice share one
#: surface and radius, and building the pool took 60 % of a candidate's time on the main job's pig
_BUILT: OrderedDict = OrderedDict()
_BUILT_MAX = 2
_LOCK = threading.Lock()


def disc_pool(vertices, radius: float) -> VertexDiscPool:
    """:class:`VertexDiscPool` of ``vertices`` and ``radius``, built once for the same surface and radius
    (the last :data:`_BUILT_MAX` kept; a pool is read-only once built).

    Examples
    --------
    >>> v = np.random.default_rng(0).uniform(0, 10, (200, 3))
    >>> disc_pool(v, 2.0) is disc_pool(v.copy(), 2.0), disc_pool(v, 2.0) is disc_pool(v, 3.0)
    (True, False)
    """
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    key = (hashlib.sha1(v.tobytes()).hexdigest(), v.shape, float(radius))
    with _LOCK:  # one build per key, even when candidates start side by side
        if key not in _BUILT:
            _BUILT[key] = VertexDiscPool(v, radius)
            while len(_BUILT) > _BUILT_MAX:
                _BUILT.popitem(last=False)
        _BUILT.move_to_end(key)
        return _BUILT[key]


__all__ = ["VertexDiscPool", "disc_pool"]
