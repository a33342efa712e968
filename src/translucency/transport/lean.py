r"""The lean in the renderer: the near transport tilted toward the light's and the camera's directions
(:mod:`translucency.model.lean`).

For a light of one direction per vertex (directional, point, spot: ``light.arrival``) and a camera at
``eye``, every near pair (o, i) of the prepared transport (:mod:`.matrices`) is weighted per channel by

.. math:: T'_{oi} = T_{oi}\, \frac{e^{g_{oi}}}{Z_i}\,
          \frac{e^{-\kappa_o \vec\ell'_o \cdot \hat d_{oi}}}{N_{oi}}, \qquad
          g_{oi} = \kappa_i \vec\ell_i \cdot \hat d_{oi} - \lambda_i (\vec\ell_i \cdot n_i)\, r_{oi}, \qquad
          Z_i = \frac{\sum_o A_o T_{oi} e^{g_{oi}}}{\sum_o A_o T_{oi}},

with :math:`\hat d_{oi}` the unit vector from :math:`x_i` to :math:`x_o`, :math:`\vec\ell_i` the lean vector
of the light at the source and :math:`\vec\ell'_o` that of the direction to the camera at the receiver, κ
and λ blended to every vertex from the fitted points (the exit's lean has no reach term). Each source still
sends its measured total (the near pairs' share of it: the far field and the own area are left diffuse), and
each pair's exit averages to its diffuse value over the hemisphere. A light of many directions (a sky,
an environment map) leans by the mean of its lean vectors weighted by the irradiance each brings
(:func:`light_lean`): its first moment, as a vector irradiance would carry it.

``render --angles`` draws the light's lean only: the exit's, the reciprocal half, is built (``exit=True``)
and measured too bright (docs/lean.md), so the default transport is not reciprocal in
the camera's direction — a measured choice, stated, not an oversight.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numba
import numpy as np
import scipy.sparse as sp
from numba import njit, prange

from ..geometry import vertex_areas
from ..model.lean import exit_normalisation, lean_vector

#: pairs handled at once while preparing (about 400 bytes each in flight)
_PAIRS_PER_BATCH = 1 << 21


@dataclass(frozen=True)
class LeanPairs:
    """What the lean needs of a transport's near pairs, independent of the light and the camera (built once
    per transport by :func:`lean_pairs`), in column order: each source's pairs together."""

    indptr: np.ndarray  # (V + 1,) each source's pairs: indptr[i] … indptr[i + 1]
    row: np.ndarray  # (nnz,) int32 the receiver's row of the matrices (where its radiance goes)
    rcv: np.ndarray  # (nnz,) int32 the receiver's mesh vertex
    d: np.ndarray  # (nnz, 3) float32 unit vectors from x_i to x_o (0 on the diagonal)
    r: np.ndarray  # (nnz,) float32 |x_o − x_i|, mm
    T: np.ndarray  # (nnz, C) float32 the near matrices' values (C = 1 shared, or 3 channels)
    AT: np.ndarray  # (nnz, C) float32 A_o T_oi, Z's weights (A_o the receiver's area, mm²)
    diagonal: np.ndarray  # (V,) int64 each source's pair with itself (−1: none), left as it is
    log_N: np.ndarray | None  # (nnz, 3) float32 ln of the exit normalisation per pair (None: no exit)
    order: np.ndarray  # (nnz,) the pairs' positions in the matrices' CSR order


def lean_pairs(transport, mesh, eta: float = 1.0, exit: bool = False) -> LeanPairs:
    r"""The transport's near pairs as the lean reads them (:class:`LeanPairs`): each source's receivers, the
    unit vectors :math:`\hat d_{oi}`, the values and, with ``exit``, the exit normalisation :math:`N_{oi}`
    (:func:`~translucency.model.lean.exit_normalisation`: most of the preparation's time)."""
    T = transport.matrices[0].tocsr()
    V = T.shape[1]
    # column order: each source's receivers in one row of the transpose, whose values are the pairs'
    # positions in the CSR order (to read the matrices' values there and to write checks back)
    position = sp.csr_matrix((np.arange(T.nnz, dtype=np.float64) + 1, T.indices, T.indptr), shape=T.shape)
    by_source = position.T.tocsr()
    rows = by_source.indices.astype(np.int32)
    order = (by_source.data - 1).astype(np.int64)
    i = np.repeat(np.arange(V), np.diff(by_source.indptr))
    rcv = rows if transport.receivers is None else np.asarray(transport.receivers)[rows].astype(np.int32)
    X = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    kappa = transport.lean[:, 0].astype(np.float64)
    d = np.zeros((len(i), 3), np.float32)
    dist = np.zeros(len(i), np.float32)
    N = np.ones((len(i), 3), np.float32) if exit else None
    for s in range(0, len(i), _PAIRS_PER_BATCH):
        oo, ii = rcv[s : s + _PAIRS_PER_BATCH], i[s : s + _PAIRS_PER_BATCH]
        v = X[oo] - X[ii]
        r = np.linalg.norm(v, axis=1, keepdims=True)
        dd = np.divide(v, r, out=np.zeros_like(v), where=r > 0)
        d[s : s + len(oo)] = dd
        dist[s : s + len(oo)] = r[:, 0]
        if exit:
            N[s : s + len(oo)] = exit_normalisation(kappa[oo], -dd, n[oo], eta)
    diagonal = np.full(V, -1, np.int64)
    on = rcv == i
    diagonal[i[on]] = np.flatnonzero(on)
    values = np.stack([M.tocsr().data[order] for M in transport.matrices], axis=1).astype(np.float32)
    AT = (vertex_areas(mesh)[rcv][:, None] * values).astype(np.float32)
    return LeanPairs(
        indptr=by_source.indptr.astype(np.int64), row=rows, rcv=rcv, d=d, r=dist, T=values, AT=AT,
        diagonal=diagonal, log_N=None if N is None else np.log(N), order=order,
    )  # fmt: skip


@dataclass(frozen=True)
class Tilt:
    r"""One light's (and camera's) lean on a transport's near pairs — what :func:`leaned` computes per light;
    :func:`~translucency.transport.relight.relight_vertices` applies it in one pass over the sources
    (:meth:`apply`), no matrix rebuilt."""

    pairs: LeanPairs
    ell: np.ndarray  # (V, 3) float32 the light's lean vector at each source
    depth: np.ndarray  # (V,) float32 ℓ · n at each source (1 − cos θ_t)
    kappa: np.ndarray  # (V, 3) float32
    lam: np.ndarray  # (V, 3) float32, mm⁻¹
    ell_view: np.ndarray | None  # (V, 3) float32 the camera's lean vector at each receiver (None: no exit)

    def _run(self, X, out, values):
        """One parallel pass over the sources (:func:`_tilt_pass`), split between the cores by their
        pairs; each core adds into its own ``parts``."""
        p = self.pairs
        with_exit = self.ell_view is not None
        K = numba.get_num_threads()
        parts = np.zeros((K, out.shape[0], 3), np.float32)
        split = np.searchsorted(p.indptr, np.linspace(0, p.indptr[-1], K + 1), side="left")
        split[0], split[-1] = 0, len(p.indptr) - 1
        longest = int(np.max(np.diff(p.indptr), initial=0))
        view, log_N = (self.ell_view, p.log_N) if with_exit else (self.ell, _NONE)  # (unread: no exit)
        _tilt_pass(split, p.indptr, p.row, p.rcv, p.d, p.r, p.T, p.AT, p.diagonal, self.ell, self.depth,
                   self.kappa, self.lam, view, log_N, with_exit, X, parts, values, longest)  # fmt: skip
        out += parts.sum(axis=0)

    def apply(self, X: np.ndarray, rows: int) -> np.ndarray:
        """The tilted near transport times X (V, 3) (the irradiance with its colour scale): (rows, 3)."""
        out = np.zeros((rows, 3), np.float32)
        self._run(np.ascontiguousarray(X, dtype=np.float32), out, np.zeros((0, 3), np.float32))
        return out

    def matrix(self, transport, c: int) -> sp.csr_matrix:
        """The tilted near matrix of channel ``c``, T'_c (for checks and analyses: the renderer never
        builds it)."""
        p = self.pairs
        values = np.zeros((len(p.r), 3), np.float32)
        self._run(np.zeros((len(p.indptr) - 1, 3), np.float32), np.zeros((1, 3), np.float32), values)
        T = transport.matrices[min(c, len(transport.matrices) - 1)].tocsr()
        data = np.empty(T.nnz, np.float32)
        data[p.order] = values[:, c]
        return sp.csr_matrix((data, T.indices, T.indptr), shape=T.shape)


_NONE = np.zeros((1, 3), np.float32)  # (for an argument a kernel does not read)


@njit(inline="always", fastmath=True)
def _exp_inplace(x, bits, n):
    """e^x for x[:n], in place, to float32's precision (relative error below 2·10⁻⁶ for |x| ≤ 30): e^x =
    2^k 2^f with k = round(x log₂e) and |f| ≤ 1/2, 2^f from its Taylor series to degree 6 (error 10⁻⁷)
    and 2^k written as the float's exponent bits — loops without a call, so that they vectorise (four to
    eight lanes: the kernel's exponentials cost what NumPy's do, without a trip through memory)."""
    for j in range(n):
        y = min(max(x[j] * np.float32(1.4426950408889634), np.float32(-126.0)), np.float32(126.0))
        k = np.floor(y + np.float32(0.5))
        t = (y - k) * np.float32(0.6931471805599453)  # f ln 2, |t| ≤ 0.35
        p = np.float32(1 / 120) + t * np.float32(1 / 720)  # Horner, from the top
        p = np.float32(1 / 6) + t * (np.float32(1 / 24) + t * p)
        x[j] = np.float32(1.0) + t * (np.float32(1.0) + t * (np.float32(1 / 2) + t * p))
        bits[j] = (np.int32(k) + np.int32(127)) << np.int32(23)  # 2^k
    scale = bits[:n].view(np.float32)
    for j in range(n):
        x[j] *= scale[j]


@njit(parallel=True, cache=True, fastmath=True)
def _tilt_pass(split, indptr, row, rcv, d, r, T, AT, diagonal, ell, depth, kappa, lam, ell_view, log_N,
               with_exit, X, parts, values, longest):  # fmt: skip
    """The estimator of :func:`leaned`, source by source, core k taking sources split[k] … split[k+1] − 1.
    Per source i, over its n pairs (o, i), in a buffer of the core's own that stays in its cache:

    1. the light's exponents per channel, g_oi = κ_i ℓ_i · d_oi − λ_i (ℓ_i · n_i) r_oi, and ``with_exit``
       the camera's, −κ_o ℓ'_o · d_oi − ln N_oi; their exponentials (:func:`_exp_inplace`);
    2. Z_i = Σ_o A_o T_oi e^{g_oi} / Σ_o A_o T_oi over its receivers (the pair with itself left out);
    3. each receiver o gets T_oi X_i e^{g_oi} / Z_i (× the camera's lobe), the diagonal T_ii X_i, added into
       the core's own slice of ``parts`` (K, rows, 3).

    With ``values`` of nnz rows, the factor itself (without X) is written there instead."""
    C, K = T.shape[1], parts.shape[0]
    c1, c2 = min(1, C - 1), min(2, C - 1)  # the matrices' columns of green and blue (one shared: 0)
    write = values.shape[0] > 0
    lanes = 6 if with_exit else 3  # exponentials per pair: the light's three (and the camera's three)
    for k in prange(K):
        # pair m − lo = u: e[3u + c] the light's, e[3n + 3u + c] the camera's
        e = np.empty(lanes * longest, np.float32)
        bits = np.empty(lanes * longest, np.int32)
        for i in range(split[k], split[k + 1]):
            lo, hi, j = indptr[i], indptr[i + 1], diagonal[i]
            n = hi - lo
            e0, e1, e2, q = ell[i, 0], ell[i, 1], ell[i, 2], depth[i]
            k0, k1, k2, l0, l1, l2 = kappa[i, 0], kappa[i, 1], kappa[i, 2], lam[i, 0], lam[i, 1], lam[i, 2]
            for m in range(lo, hi):  # 1. the exponents
                a = d[m, 0] * e0 + d[m, 1] * e1 + d[m, 2] * e2
                reach = q * r[m]
                u = 3 * (m - lo)
                e[u], e[u + 1], e[u + 2] = k0 * a - l0 * reach, k1 * a - l1 * reach, k2 * a - l2 * reach
                if with_exit:
                    o = rcv[m]
                    b = -(d[m, 0] * ell_view[o, 0] + d[m, 1] * ell_view[o, 1] + d[m, 2] * ell_view[o, 2])
                    for c in range(3):
                        e[3 * n + u + c] = kappa[o, c] * b - log_N[m, c]
            _exp_inplace(e, bits, lanes * n)
            n0 = n1 = n2 = d0 = d1 = d2 = np.float32(0.0)
            if C == 1:  # 2. Z's sums (the diagonal's lobe is 1: taken out below); one matrix: one weight
                for m in range(lo, hi):
                    u, t0 = 3 * (m - lo), AT[m, 0]
                    n0, n1, n2, d0 = n0 + t0 * e[u], n1 + t0 * e[u + 1], n2 + t0 * e[u + 2], d0 + t0
                d1 = d2 = d0
            else:
                for m in range(lo, hi):
                    u, t0, t1, t2 = 3 * (m - lo), AT[m, 0], AT[m, 1], AT[m, 2]
                    n0, n1, n2 = n0 + t0 * e[u], n1 + t1 * e[u + 1], n2 + t2 * e[u + 2]
                    d0, d1, d2 = d0 + t0, d1 + t1, d2 + t2
            if j >= 0:
                t0, t1, t2 = AT[j, 0], AT[j, c1], AT[j, c2]
                n0, n1, n2, d0, d1, d2 = n0 - t0, n1 - t1, n2 - t2, d0 - t0, d1 - t1, d2 - t2
            z0 = d0 / n0 if n0 > 0.0 and d0 > 0.0 else np.float32(1.0)  # 1 / Z_i per channel
            z1 = d1 / n1 if n1 > 0.0 and d1 > 0.0 else np.float32(1.0)
            z2 = d2 / n2 if n2 > 0.0 and d2 > 0.0 else np.float32(1.0)
            x0, x1, x2 = X[i, 0] * z0, X[i, 1] * z1, X[i, 2] * z2
            if C == 1 and not (with_exit or write):  # 3. the receivers (the plain case written out)
                for m in range(lo, hi):
                    u, o, t = 3 * (m - lo), row[m], T[m, 0]
                    parts[k, o, 0] += t * e[u] * x0
                    parts[k, o, 1] += t * e[u + 1] * x1
                    parts[k, o, 2] += t * e[u + 2] * x2
            else:
                for m in range(lo, hi):
                    u = 3 * (m - lo)
                    f0, f1, f2 = T[m, 0] * e[u], T[m, c1] * e[u + 1], T[m, c2] * e[u + 2]
                    if with_exit:
                        f0, f1, f2 = f0 * e[3 * n + u], f1 * e[3 * n + u + 1], f2 * e[3 * n + u + 2]
                    if write:
                        values[m, 0], values[m, 1], values[m, 2] = f0 * z0, f1 * z1, f2 * z2
                    else:
                        o = row[m]
                        parts[k, o, 0] += f0 * x0
                        parts[k, o, 1] += f1 * x1
                        parts[k, o, 2] += f2 * x2
            if j >= 0:  # a vertex's pair with itself keeps its value: T_ii X_i
                o, u = row[j], 3 * (j - lo)
                for c in range(3):
                    tc = T[j, min(c, c2)]
                    if write:
                        values[j, c] = tc
                    else:
                        zc = z0 if c == 0 else (z1 if c == 1 else z2)
                        lobe = e[u + c] * (e[3 * n + u + c] if with_exit else np.float32(1.0))
                        parts[k, o, c] += tc * X[i, c] * (np.float32(1.0) - lobe * zc)


def lean_applies(transport, light) -> bool:
    """Whether :func:`leaned` tilts this transport for this light: the model has a lean and the light
    arrives along one direction per vertex (directional, point, spot) or says from which it arrives on
    average (an environment light: :meth:`mean_over_arrivals`)."""
    one = bool(getattr(light, "delta", False))
    return transport.lean is not None and (one or hasattr(light, "mean_over_arrivals"))


def light_lean(light, mesh, scene, eta: float = 1.0) -> np.ndarray:
    r"""The light's lean vector at every vertex (V, 3): :math:`\vec\ell = \omega_t + n` of its one
    direction, or, for light from many directions, its mean weighted by the irradiance each brings,
    :math:`\bar\ell = \int E(\omega)\, \vec\ell(\omega)\, d\omega / E` — the first moment in place of the
    lobes' mean (for a uniform sky on an open plane :math:`\bar\ell = n/3` at η = 1; the mean of the lobes
    themselves straight through the body differs from the lobe of the mean by 4 % at κ = 1.2)."""
    X = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    if getattr(light, "delta", False):
        return lean_vector(light.arrival(scene, X, n)[0], n, eta)
    extent = float(np.max(mesh.extents))
    return light.mean_over_arrivals(scene, X, n, extent, lambda w, nn: lean_vector(w, nn, eta), eta)


def leaned(transport, mesh, scene, light, eye, *, eta: float = 1.0, exit: bool = False, pairs=None):
    """The transport with the lean of ``light`` and the camera at ``eye`` (mm), or None where it does not
    apply (no κ in the model, or a light that says nothing of its directions).

    Parameters
    ----------
    transport : Transport
        Prepared by :func:`~translucency.transport.matrices.transport_matrices` from a model with a lean
        (``transport.lean``: κ and λ, (V, 2, 3)).
    mesh, scene
        The object and its Mitsuba scene.
    light : Light
        A light with ``arrival`` (directional, point, spot) or ``mean_over_arrivals`` (environment).
    eye : array_like, shape (3,)
        The camera's position, mm.
    eta : float
        Relative index of the boundary (1: index-matched).
    exit : bool
        Also the exit's lean toward the camera (off by default: it draws the back-lit spots 29–70 % too
        bright, docs/lean.md; the light's lean alone is not reciprocal).
    pairs : LeanPairs, optional
        :func:`lean_pairs`' result, to reuse between lights and cameras.

    Returns
    -------
    Transport or None
        The same matrices, own area and far field, with the light's :class:`Tilt` (``tilt``), which
        :func:`~translucency.transport.relight.relight_vertices` applies to the near pairs.

    Examples
    --------
    A ball scanned with oblique beams (so its fit has a lean), lit from above and seen from the side:

    >>> import tempfile, trimesh
    >>> import numpy as np
    >>> import translucency as tl
    >>> from translucency.mitsuba import mesh_scene
    >>> from translucency.render import parse_light
    >>> from translucency.transport.lean import leaned
    >>> from translucency.transport.matrices import transport_matrices
    >>> from translucency.transport.relight import relight_vertices
    >>> ball = trimesh.creation.icosphere(2, radius=4.0)
    >>> data = tl.acquire_mesh(ball, tempfile.mkdtemp() + "/ball.zarr", "homogeneous:marble", voxel_mm=1.0,
    ...                        points=4, photons=300, index_matched=True, incidence=(45,), azimuths=2)
    >>> model, mesh = tl.fit_model(data, "iso", n_terms=1, max_rounds=1).model, data.mesh()
    >>> T = transport_matrices(model, mesh)
    >>> T_lean = leaned(T, mesh, mesh_scene(mesh), parse_light("directional:0,0,-1,1"), [40.0, 0.0, 0.0])
    >>> T_lean.tilt is not None
    True
    >>> L = relight_vertices(T_lean, np.ones(len(mesh.vertices)))
    >>> L.shape
    (162, 3)
    """
    if not lean_applies(transport, light):
        return None
    exit_eye = eye if exit else None
    return tilted(transport, mesh, light_lean(light, mesh, scene, eta), eta=eta, eye=exit_eye, pairs=pairs)


def tilted(transport, mesh, ell, *, eta: float = 1.0, eye=None, pairs=None):
    """The transport with the lean of light whose lean vector at each vertex is ``ell`` (V, 3) (the mesh's
    frame: :func:`light_lean`, or a scene's irradiance-weighted mean), and with ``eye`` (mm) the camera's
    too: :func:`leaned` for a light already reduced to its lean vectors.  ``pairs``: :func:`lean_pairs`'
    result, to reuse."""
    if len({T.nnz for T in transport.matrices}) > 1:
        raise ValueError("leaned: the channels' near matrices must share their pairs")
    exit = eye is not None
    p = lean_pairs(transport, mesh, eta, exit) if pairs is None else pairs
    if exit and p.log_N is None:
        p = lean_pairs(transport, mesh, eta, exit=True)
    X = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    depth = np.einsum("vk,vk->v", ell, n).astype(np.float32)  # ℓ · n = 1 − cos θ_t
    ell_view = None
    if exit:  # the camera's lean vector at the receivers
        to_eye = np.asarray(eye, dtype=np.float64)[None, :] - X
        to_eye /= np.linalg.norm(to_eye, axis=1, keepdims=True)
        ell_view = lean_vector(to_eye, n, eta).astype(np.float32)
    kappa, lam = (np.ascontiguousarray(transport.lean[:, k], dtype=np.float32) for k in (0, 1))
    ell = np.ascontiguousarray(ell, dtype=np.float32)
    tilt = Tilt(pairs=p, ell=ell, depth=depth, kappa=kappa, lam=lam, ell_view=ell_view)
    return dataclasses.replace(transport, tilt=tilt)
