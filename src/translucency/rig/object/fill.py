r"""The fill of unseen cells: R_d over the mesh graph where no camera measured it (flag UNSEEN).

The harmonic fill holds the measured values and gives each missing one the mean of its neighbours' on
the mesh's edge graph, :math:`(I - N_{UU}) x_U = N_{UK} x_K`.  Units those of R_d (mm⁻²); the fit
leaves the filled pairs out, the stored value keeps the energy bookkeeping whole, and its variance
(:meth:`HarmonicFill.variance`) says how well: the neighbours' variances filled the same way plus the
local spread of the filled field, :math:`(N x^2)_v - (N x)_v^2`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp


class HarmonicFill:
    """The harmonic fill over the mesh graph: each missing value is the mean of its neighbours', the
    measured held — :math:`(I - N_{UU}) x_U = N_{UK} x_K`, one sparse LU per set of missing vertices (the
    unseen set is the same for every shot; it changes only where a shot saturates), kept for the next.
    A component of the mesh with no measured vertex gets 0."""

    def __init__(self, mesh):
        from scipy.sparse.csgraph import connected_components  # heavy: SciPy's graphs load where filled

        e = np.asarray(mesh.edges_unique)
        V = len(mesh.vertices)
        rows, cols = np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]]
        A = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(V, V)).tocsr()
        deg = np.asarray(A.sum(axis=1)).ravel()
        self.N = (sp.diags(1.0 / np.maximum(deg, 1)) @ A).tocsr()  # row-normalised adjacency
        self.components = connected_components(self.N, directed=False)[1]
        self._cache: dict = {}

    def __call__(self, R: np.ndarray, missing: np.ndarray) -> np.ndarray:
        from scipy.sparse.linalg import splu  # heavy: SciPy's sparse LU loads where values are filled

        if not missing.any():
            return R.astype(np.float32)
        key = np.packbits(missing).tobytes()
        if key not in self._cache:
            comp = self.components
            has_known = np.zeros(comp.max() + 1, dtype=bool)
            has_known[comp[~missing]] = True
            U = np.flatnonzero(missing & has_known[comp])
            K = np.flatnonzero(~missing)
            NU = self.N[U]
            lu = splu((sp.identity(len(U), format="csc") - NU[:, U]).tocsc()) if len(U) else None
            self._cache = {key: (U, K, NU[:, K], lu)}  # one pattern kept: shots rarely alternate
        U, K, NUK, lu = self._cache[key]
        x = np.where(missing[:, None], 0.0, R).astype(np.float64)
        if len(U):
            x[U] = lu.solve(np.asarray(NUK @ x[K]))
        return x.astype(np.float32)

    def variance(self, R: np.ndarray, var: np.ndarray, missing: np.ndarray) -> np.ndarray:
        """The variance of the filled values ``R`` (as returned by the call) at the ``missing`` cells: the
        measured variances ``var`` filled harmonically, plus the spread of R over each cell's neighbours
        (mm⁻⁴); ``var`` elsewhere."""
        out = np.where(np.isfinite(var), var, 0.0)
        if not missing.any():
            return out.astype(np.float32)
        filled = self(out, missing).astype(np.float64)
        x = np.asarray(R, dtype=np.float64)
        spread = np.maximum(self.N @ (x * x) - (self.N @ x) ** 2, 0.0)
        out[missing] = filled[missing] + spread[missing]
        return out.astype(np.float32)
