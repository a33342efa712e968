r"""The far field of the transport: the light that crosses a body beyond the near radius R.

The sparse near matrix of :func:`translucency.transport.matrices.transport_matrices` holds the vertex
pairs closer than R.  The rest of the sum

.. math:: L^{far}(x_o) = \alpha_o \sum_{i:\,|x_o - x_i| > R} b_i\, X_i\, P_i(|x_o - x_i|), \qquad
          b_i = g_i A_i / \pi,

(:math:`X_i` the irradiance times the colour scale that rides with it, :math:`g_i` the column
normalisation, :math:`P_i` the vertex's blended profile, mm⁻²) is evaluated on two levels, as the
clustered irradiance of Jensen & Buhler (2002):

* **sources** — K clusters J (farthest-point seeds :math:`p_J`, every vertex joins its nearest seed);
  a light only sums each cluster's power :math:`\Phi_J = \sum_{i \in J} b_i X_i` (``B``, K × V sparse);
* **cluster to seed** — :math:`F_{OJ}`, the radiance at seed :math:`p_O` per unit power of cluster J:
  the area-weighted mean profile of J's members at the distance from their area centroid
  :math:`\bar x_J`, :math:`\bar P_J(|p_O - \bar x_J|)`, where the whole cluster lies beyond R and is
  small as seen from :math:`p_O` (:math:`\rho_J \le \theta D`, ρ_J its radius); otherwise the members
  one by one, :math:`\sum_{i \in J} (A_i / A_J)\, P_i(|p_O - x_i|)\, [\,|p_O - x_i| > R\,]`
  (zero when the whole cluster lies within R);
* **back to the vertices** — the far field is a smooth function of position in space, so each vertex
  takes a linear moving-least-squares fit of the k nearest seeds' values (``W``, V × K sparse, weights
  summing to 1), then its own :math:`\alpha_o`.

Relighting is :math:`L^{far} = \alpha \odot W\, F\, B\, X` — two sparse products of V and k·V entries and
one dense K × K product per channel.  The estimator is exact in the members' profiles and positions
for cluster pairs that are opened; its errors are the spread of power within a source cluster (members
weighted by area, not by their irradiance) and the interpolation between seeds.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
import scipy.sparse as sp
from numba import njit, prange
from scipy.spatial import cKDTree
from threadpoolctl import ThreadpoolController

from .._validate import TranslucencyError
from ..model.through import through_factor

#: opening criterion: a cluster of radius ρ at distance D is taken whole when ρ ≤ θ D
THETA = 0.5
#: seeds that each vertex interpolates from
K_NEAREST = 8
#: most clusters (the dense operator holds K² float32 per channel: 36 MB at 3,000)
MAX_CLUSTERS = 3000


@dataclass(kw_only=True)
class FarField:
    r"""The prepared far field: :math:`L^{far} = \alpha \odot W F B X` (module docstring)."""

    W: sp.csr_matrix  # (V × K) float32: seeds → vertices, linear moving least squares
    F: list  # one or three (K × K) float32: radiance at seed O per unit power of cluster J, mm⁻²
    B: list  # one or three (K × V) CSR float32: power of each cluster, b_i = g_i A_i / π (mm²)
    alpha: np.ndarray  # (V,) float32: α at each receiving vertex
    label: np.ndarray  # (V,) cluster of each vertex
    radius: float  # R, mm: the near matrix holds the pairs within it

    @property
    def clusters(self) -> int:
        """K, the number of clusters (and seeds)."""
        return int(self.W.shape[1])

    @property
    def nbytes(self) -> int:
        """Memory held by the operator, bytes."""
        mats = [self.W, *self.B]
        return int(
            sum(m.data.nbytes + m.indices.nbytes + m.indptr.nbytes for m in mats)
            + sum(f.nbytes for f in self.F)
            + self.alpha.nbytes
            + self.label.nbytes
        )

    def spread(self, ch: int, area: np.ndarray) -> np.ndarray:
        r"""Per incident vertex i: :math:`\sum_o A_o \alpha_o (W F)_{o J(i)}`, the far field's exitance
        per unit :math:`b_i X_i \pi / A_i` — the far share of column i's energy, before normalisation."""
        u = self.W.T @ (area * self.alpha)  # (K,) mm²: what each seed's value weighs on the surface
        return (u @ self.F[ch].astype(np.float64))[self.label]

    def normalise(self, ch: int, factor: np.ndarray) -> None:
        """Scale each source vertex's power by ``factor`` (V,) in matrix ``ch`` (the column normalisation)."""
        B = self.B[ch].tocsc()
        B.data *= np.repeat(factor, np.diff(B.indptr)).astype(np.float32)
        self.B[ch] = B.tocsr()

    def apply(self, X: np.ndarray) -> np.ndarray:
        """Radiance (V, 3) for X (V, 3): irradiance (W/mm²) times what rides with it.

        The K × K product runs on one BLAS thread: it is three columns wide, and BLAS's threads go on
        spinning after it, which halved the speed of the Numba kernels relighting the next light
        (measured: the lean's pass 53 → 83–106 ms on the 89 k-vertex pig)."""
        with _blas().limit(limits=1, user_api="blas"):
            if len(self.F) == 1:  # shared fall-off: the three channels through one operator
                G = self.F[0] @ (self.B[0] @ X)
            else:
                G = np.stack([F @ (B @ X[:, ch]) for ch, (F, B) in enumerate(zip(self.F, self.B))], axis=1)
        return (self.W @ G) * self.alpha[:, None]


@cache
def _blas() -> ThreadpoolController:
    """The BLAS libraries loaded (found once: the search reads every loaded library)."""
    return ThreadpoolController()


def default_clusters(V: int, surface: float, radius: float) -> int:
    """K: seeds spaced about half the near radius apart (K ≈ 4 · surface / (π R²)), 256 to 3,000."""
    if not radius > 0:  # no near part: the finest clustering allowed
        return int(min(V, MAX_CLUSTERS))
    with np.errstate(over="ignore", divide="ignore"):  # a radius so small that K overflows: the cap
        K = np.ceil(4.0 * surface / (np.pi * np.float64(radius) ** 2))
    return int(min(V, np.clip(K, 256, MAX_CLUSTERS)))


def far_field_operator(model, *, v, area, alpha, weights, c, d, radius, surface, clusters=None, through=None):
    r"""The far field of a transport with near radius ``radius`` (mm), before normalisation
    (:math:`b_i = A_i/\pi`); ``None`` when every pair of vertices lies within it.

    ``weights`` = (w, idx): each vertex's blend of incident points, ``c, d``: the blended profiles
    (V, C, T) (:func:`translucency.transport.parameters.vertex_parameters`), ``surface``: the mesh's area
    (mm²), ``clusters``: K (default :func:`default_clusters`).  ``through`` = (table (V, 4, 8, 3), normals
    (V, 3)): the through-body table (:mod:`translucency.model.through`) at the cluster level — each
    :math:`F_{OJ}` times cluster J's area-weighted mean table at the cosine between the seed's normal and
    J's mean normal and at the distance from J's centroid; three channels then.
    """
    V = len(v)
    if clusters is not None and int(clusters) < 1:
        raise TranslucencyError(f"clusters: need at least 1 far-field cluster, got {clusters}")
    if np.linalg.norm(v.max(0) - v.min(0)) <= radius:
        return None
    K = int(min(V, clusters if clusters is not None else default_clusters(V, surface, radius)))
    # clusters: farthest-point seeds, each vertex to its nearest seed; area centroid and radius (mm)
    seeds = _farthest_points(v, K)
    p = v[seeds]
    label = cKDTree(p).query(v)[1]
    area_J = np.bincount(label, area, K)
    centroid = np.stack([np.bincount(label, area * v[:, j], K) for j in range(3)], 1) / area_J[:, None]
    rho = np.zeros(K)
    np.maximum.at(rho, label, np.linalg.norm(v - centroid[label], axis=1))
    order = np.argsort(label, kind="stable")
    mem_ptr = np.concatenate([[0], np.cumsum(np.bincount(label, minlength=K))])
    mem_w = area[order] / area_J[label[order]]  # A_i / A_J
    # each cluster's mean profile as a blend of the incident points' profiles: Σ_i (A_i/A_J) w_ip
    w, idx = weights
    rep = sp.csr_matrix(
        ((area[:, None] * w).ravel(), (np.repeat(label, w.shape[1]), idx.ravel())),
        shape=(K, model.n_points),
    )
    rep.sum_duplicates()
    rep = sp.diags(1.0 / area_J) @ rep
    F = []
    for ch in range(c.shape[1]):
        out = np.empty((K, K))
        _cluster_to_seed(
            seeds=p,
            centroid=centroid,
            rho=rho,
            radius=float(radius),
            representatives=rep,
            point_c=np.ascontiguousarray(model.c[:, ch, 0]),
            point_d=np.ascontiguousarray(model.d[:, ch, 0]),
            members=(mem_ptr, order, mem_w),
            x=v,
            vertex_c=np.ascontiguousarray(c[:, ch]),
            vertex_d=np.ascontiguousarray(d[:, ch]),
            out=out,
        )
        F.append(out.astype(np.float32))
    if through is not None:  # light through the body, cluster to seed
        table, normals = through
        n_J = np.stack([np.bincount(label, area * normals[:, j], K) for j in range(3)], 1)
        n_J /= np.maximum(np.linalg.norm(n_J, axis=1, keepdims=True), 1e-12)
        members = sp.csr_matrix((area, (label, np.arange(V))), shape=(K, V))  # A_i of J's members
        t_J = (members @ table.reshape(V, -1)).reshape((K,) + table.shape[1:]) / area_J[:, None, None, None]
        cos = (normals[seeds] @ n_J.T).ravel()  # (O, J)
        dist = np.linalg.norm(p[:, None] - centroid[None], axis=2).ravel()
        src = np.tile(np.arange(K), K)
        F = [
            F[min(ch, len(F) - 1)]
            * through_factor(t_J[..., ch], src, cos, dist).reshape(K, K).astype(np.float32)
            for ch in range(3)
        ]
    B = sp.csr_matrix((area / np.pi, (label, np.arange(V))), shape=(K, V), dtype=np.float32)
    return FarField(
        W=mls_weights(v, p),
        F=F,
        B=[B.copy() for _ in F],
        alpha=alpha.astype(np.float32),
        label=label,
        radius=float(radius),
    )


@njit(cache=True)
def _farthest_points(x, k):
    """Indices of k points by farthest-point sampling from point 0 (Euclidean), compiled: the K seeds of
    a large mesh in well under a second (``geometry.farthest_points`` is the same rule, in NumPy)."""
    n = x.shape[0]
    chosen = np.empty(k, dtype=np.int64)
    dist = np.full(n, np.inf)
    nxt = 0
    for j in range(k):
        chosen[j] = nxt
        best, arg = -1.0, 0
        for i in range(n):
            dd = (x[i, 0] - x[nxt, 0]) ** 2 + (x[i, 1] - x[nxt, 1]) ** 2 + (x[i, 2] - x[nxt, 2]) ** 2
            if dd < dist[i]:
                dist[i] = dd
            if dist[i] > best:
                best, arg = dist[i], i
        nxt = arg
    return chosen


def _cluster_to_seed(
    *, seeds, centroid, rho, radius, representatives, point_c, point_d, members, x, vertex_c, vertex_d, out
) -> None:
    """Fill ``out`` (K, K) with F of one channel (:func:`_cluster_to_seed_kernel`), every array by name.

    ``seeds``, ``centroid`` (K, 3) mm and ``rho`` (K,) mm: the clusters' seeds, area centroids and radii;
    ``representatives``: (K × N) CSR, each cluster's mean profile as weights of the incident points;
    ``point_c``, ``point_d`` (N, n): the incident points' terms; ``members`` = (ptr (K + 1,), vertex
    (V,), A_i / A_J (V,)): the members of each cluster; ``x`` (V, 3) mm and ``vertex_c``, ``vertex_d``
    (V, T): the vertices and their blended terms.
    """
    mem_ptr, mem_i, mem_w = members
    _cluster_to_seed_kernel(
        seeds,
        centroid,
        rho,
        radius,
        THETA,
        representatives.indptr,
        representatives.indices,
        representatives.data,
        point_c,
        point_d,
        mem_ptr,
        mem_i,
        mem_w,
        x,
        vertex_c,
        vertex_d,
        out,
    )


@njit(parallel=True, cache=True)
def _cluster_to_seed_kernel(
    p, centroid, rho, R, theta, rep_ptr, rep_p, rep_w, cp, dp, mem_ptr, mem_i, mem_w, x, cv, dv, out
):
    """out[O, J]: radiance at seed O per unit power of cluster J (mm⁻²), the rule of the module docstring.
    cp, dp: incident points' terms (N, n); cv, dv: the vertices' blended terms (V, T).  Called only by
    :func:`_cluster_to_seed`, which names every argument (Numba takes no keyword-only ones)."""
    K = p.shape[0]
    for O in prange(K):
        for J in range(K):
            D = np.sqrt(
                (p[O, 0] - centroid[J, 0]) ** 2
                + (p[O, 1] - centroid[J, 1]) ** 2
                + (p[O, 2] - centroid[J, 2]) ** 2
            )
            acc = 0.0
            if D - rho[J] > R and rho[J] <= theta * D:
                # the whole cluster, at its centroid, with its members' mean profile
                for q in range(rep_ptr[J], rep_ptr[J + 1]):
                    pp = rep_p[q]
                    s = 0.0
                    for t in range(cp.shape[1]):
                        s += cp[pp, t] * np.exp(dp[pp, t] * D)
                    acc += rep_w[q] * s
            elif D + rho[J] > R:
                # opened: member by member, those beyond R
                for q in range(mem_ptr[J], mem_ptr[J + 1]):
                    i = mem_i[q]
                    r = np.sqrt(
                        (p[O, 0] - x[i, 0]) ** 2 + (p[O, 1] - x[i, 1]) ** 2 + (p[O, 2] - x[i, 2]) ** 2
                    )
                    if r > R:
                        s = 0.0
                        for t in range(cv.shape[1]):
                            s += cv[i, t] * np.exp(dv[i, t] * r)
                        acc += mem_w[q] * s
            out[O, J] = acc


def mls_weights(x: np.ndarray, p: np.ndarray, k: int = K_NEAREST) -> sp.csr_matrix:
    r"""Interpolation weights (len(x) × len(p), CSR float32) of a linear moving-least-squares fit.

    At each point x the values at its k nearest seeds p_j are fitted by :math:`a + g \cdot (p_j - x)`
    with weights :math:`(1 - (|p_j - x|/h)^2)^2`, h = 1.5 × the k-th distance, and a small ridge on g
    (seeds on a surface leave its normal direction free); the fitted a is :math:`\sum_j \beta_j f_j` with
    :math:`\sum_j \beta_j = 1` exactly, and linear functions are reproduced up to the ridge.

    Examples
    --------
    >>> p = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> W = mls_weights(np.array([[0.25, 0.5, 0.0]]), p, k=4)
    >>> round(float((W @ (1 + 2 * p[:, 0]))[0]), 2)  # the linear function 1 + 2x at x = 0.25 (to 1e-3)
    1.5
    """
    k = min(k, len(p))
    dist, idx = cKDTree(p).query(x, k=k)
    dist, idx = dist.reshape(len(x), k), idx.reshape(len(x), k)
    h = 1.5 * dist[:, -1:] + 1e-12
    w = (1.0 - (dist / h) ** 2) ** 2
    Y = np.concatenate([np.ones((len(x), k, 1)), (p[idx] - x[:, None]) / h[:, :, None]], axis=2)  # (n, k, 4)
    M = np.einsum("nk,nka,nkb->nab", w, Y, Y)
    M[:, 1:, 1:] += 1e-3 * w.sum(1)[:, None, None] * np.eye(3)
    z = np.linalg.solve(M, np.broadcast_to(np.eye(4)[0], (len(x), 4))[..., None])[..., 0]
    beta = w * np.einsum("nka,na->nk", Y, z)
    return sp.csr_matrix(
        (beta.ravel().astype(np.float32), (np.repeat(np.arange(len(x)), k), idx.ravel())),
        shape=(len(x), len(p)),
    )
