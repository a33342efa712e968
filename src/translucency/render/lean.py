r"""The lean in the renderer: the near transport tilted toward the light's and the camera's directions
(:mod:`translucency.model.lean`).

For a light of one direction per vertex (directional, point, spot: ``light.arrival``) and a camera at
``eye``, every near pair (o, i) of the prepared transport (:mod:`.transport`) is weighted per channel by

.. math:: T'_{oi} = T_{oi}\, \frac{e^{g_{oi}}}{Z_i}\,
          \frac{e^{-\kappa_o \vec\ell'_o \cdot \hat d_{oi}}}{N_{oi}}, \qquad
          g_{oi} = \kappa_i \vec\ell_i \cdot \hat d_{oi} - \lambda_i (\vec\ell_i \cdot n_i)\, r_{oi}, \qquad
          Z_i = \frac{\sum_o A_o T_{oi} e^{g_{oi}}}{\sum_o A_o T_{oi}},

with :math:`\hat d_{oi}` the unit vector from :math:`x_i` to :math:`x_o`, :math:`\vec\ell_i` the lean vector
of the light at the source and :math:`\vec\ell'_o` that of the direction to the camera at the receiver, κ
and λ blended to every vertex from the fitted points (the exit's lean has no reach term). Each source still
sends its measured total (the near pairs' share of it: the far field and the own area are left diffuse), and
each pair's exit averages to its diffuse value over the hemisphere. A light of many directions (an
environment map) has no one lean vector: it draws the paper's model (:func:`leaned` returns None and says
why).

``render --angles`` draws the light's lean only: the exit's, the reciprocal half, is built (``exit=True``)
and measured too bright (docs/objects.md, "The lean"), so the default transport is not reciprocal in
the camera's direction — a measured choice, stated, not an oversight.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numba import njit, prange

from ..geometry import vertex_areas
from ..model.lean import exit_normalisation, lean_vector

#: pairs handled at once (about 400 bytes each in flight)
_PAIRS_PER_BATCH = 1 << 21


@dataclass(frozen=True)
class LeanPairs:
    """What the lean needs of a transport's near pairs, independent of the light and the camera (built once
    per transport by :func:`lean_pairs`)."""

    o: np.ndarray  # (nnz,) receivers (mesh vertex indices)
    i: np.ndarray  # (nnz,) sources
    d: np.ndarray  # (nnz, 3) float32 unit vectors from x_i to x_o (0 on the diagonal)
    r: np.ndarray  # (nnz,) float32 |x_o − x_i|, mm
    N: np.ndarray | None  # (nnz, 3) float32 the exit normalisation per pair and channel (None: not needed)
    weight: np.ndarray  # (nnz, 3) float32 A_o T_oi (with the colour scale): Z's weights
    spread: np.ndarray  # (V, 3) Σ_o A_o T_oi per source: Z's denominator


def lean_pairs(transport, mesh, eta: float = 1.0, exit: bool = False) -> LeanPairs:
    r"""The transport's near pairs as the lean reads them (:class:`LeanPairs`): rows, columns, the unit
    vectors :math:`\hat d_{oi}`, the weights of :math:`Z_i` and, with ``exit``, the exit normalisation
    :math:`N_{oi}` (:func:`~translucency.model.lean.exit_normalisation`: most of the preparation's time)."""
    T = transport.matrices[0].tocsr()
    o = np.repeat(np.arange(T.shape[0]), np.diff(T.indptr))
    i = T.indices.astype(np.int64)
    X = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    if transport.receivers is not None:
        o = np.asarray(transport.receivers)[o]
    kappa = transport.lean[:, 0].astype(np.float64)
    area = vertex_areas(mesh)
    d = np.zeros((len(o), 3), np.float32)
    dist = np.zeros(len(o), np.float32)
    N = np.ones((len(o), 3), np.float32) if exit else None
    for s in range(0, len(o), _PAIRS_PER_BATCH):
        oo, ii = o[s : s + _PAIRS_PER_BATCH], i[s : s + _PAIRS_PER_BATCH]
        v = X[oo] - X[ii]
        r = np.linalg.norm(v, axis=1, keepdims=True)
        dd = np.divide(v, r, out=np.zeros_like(v), where=r > 0)
        d[s : s + len(oo)] = dd
        dist[s : s + len(oo)] = r[:, 0]
        if exit:
            N[s : s + len(oo)] = exit_normalisation(kappa[oo], -dd, n[oo], eta)
    off = np.any(d != 0, axis=1)
    weight = np.empty((len(o), 3), np.float32)
    for c in range(3):
        vals = transport.matrices[min(c, len(transport.matrices) - 1)].tocsr().data.astype(np.float64)
        if transport.scale is not None:  # the shared-colour model: Z weighs with its scale too
            vals = vals * transport.scale[i, c]
        weight[:, c] = area[o] * vals * off
    spread = np.stack([np.bincount(i, weight[:, c], minlength=len(X)) for c in range(3)], axis=1)
    return LeanPairs(o=o, i=i, d=d, r=dist, N=N, weight=weight, spread=spread)


@njit(parallel=True, cache=True, fastmath=True)
def _lobes(i, d, r, ell, depth, kappa, lam, lobe):
    """Per pair and channel the light's lobe e^{κ_i ℓ_i · d − λ_i (ℓ_i · n_i) r} into ``lobe`` (nnz, 3);
    ``depth`` (V,) is ℓ · n per source; 1 on the diagonal."""
    for m in prange(i.shape[0]):
        dx, dy, dz = d[m, 0], d[m, 1], d[m, 2]
        if dx == 0.0 and dy == 0.0 and dz == 0.0:
            for c in range(3):
                lobe[m, c] = 1.0
            continue
        src = i[m]
        a = dx * ell[src, 0] + dy * ell[src, 1] + dz * ell[src, 2]
        reach = depth[src] * r[m]
        for c in range(3):
            lobe[m, c] = np.exp(kappa[src, c] * a - lam[src, c] * reach)


@njit(cache=True)
def _source_means(i, weight, lobe, spread, Z):
    """Z_i per channel (V, 3): Σ_o A_o T_oi lobe_oi / Σ_o A_o T_oi (1 where a source has no pairs)."""
    acc = np.zeros(Z.shape)
    for m in range(i.shape[0]):
        s = i[m]
        for c in range(3):
            acc[s, c] += weight[m, c] * lobe[m, c]
    for s in range(Z.shape[0]):
        for c in range(3):
            Z[s, c] = acc[s, c] / spread[s, c] if acc[s, c] > 0.0 and spread[s, c] > 0.0 else 1.0


@njit(parallel=True, cache=True, fastmath=True)
def _tilted(i, o, d, ell_view, kappa, N, with_exit, lobe, Z, T0, T1, T2, out):
    """The leaned matrices' values (3, nnz): T_c · lobe / Z_i (· the camera's lobe, ``with_exit``)."""
    for m in prange(i.shape[0]):
        src, rcv = i[m], o[m]
        b = -(d[m, 0] * ell_view[rcv, 0] + d[m, 1] * ell_view[rcv, 1] + d[m, 2] * ell_view[rcv, 2])
        diagonal = d[m, 0] == 0.0 and d[m, 1] == 0.0 and d[m, 2] == 0.0
        for c in range(3):
            f = lobe[m, c] / Z[src, c]
            if with_exit and not diagonal:
                f *= np.exp(kappa[rcv, c] * b) / N[m, c]
            t = T0[m] if c == 0 else (T1[m] if c == 1 else T2[m])
            out[c, m] = t * (1.0 if diagonal else f)


def lean_applies(transport, light) -> bool:
    """Whether :func:`leaned` tilts this transport for this light: the model has a lean and the light
    one direction per vertex."""
    return transport.lean is not None and bool(getattr(light, "delta", False))


def leaned(transport, mesh, scene, light, eye, *, eta: float = 1.0, exit: bool = False, pairs=None):
    """The transport with the lean of ``light`` and the camera at ``eye`` (mm), or None where it does not
    apply (no κ in the model, or a light of many directions).

    Parameters
    ----------
    transport : Transport
        Prepared by :func:`~translucency.render.transport.transport_matrices` from a model with a lean
        (``transport.lean``: κ and λ, (V, 2, 3)).
    mesh, scene
        The object and its Mitsuba scene.
    light : Light
        A light with ``arrival`` (directional, point, spot).
    eye : array_like, shape (3,)
        The camera's position, mm.
    eta : float
        Relative index of the boundary (1: index-matched).
    exit : bool
        Also the exit's lean toward the camera (off by default: it draws the back-lit spots 29–70 % too
        bright, docs/objects.md "The lean"; the light's lean alone is not reciprocal).
    pairs : LeanPairs, optional
        :func:`lean_pairs`' result, to reuse between lights and cameras.

    Returns
    -------
    Transport or None
        Three matrices (one per channel; a shared-colour model keeps its scale), the same own area and
        far field.

    Examples
    --------
    >>> T_lean = leaned(T, mesh, scene, light, camera.origin)  # doctest: +SKIP
    >>> L = relight_vertices(T_lean, E)  # doctest: +SKIP
    """
    if not lean_applies(transport, light):
        return None
    p = lean_pairs(transport, mesh, eta, exit) if pairs is None else pairs
    if exit and p.N is None:
        p = lean_pairs(transport, mesh, eta, exit=True)
    X = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    V = len(X)
    w_light = light.arrival(scene, X, n)[0]
    ell = lean_vector(w_light, n, eta)  # (V, 3) at the sources
    depth = np.einsum("vk,vk->v", ell, n).astype(np.float32)  # ℓ · n = 1 − cos θ_t
    ell = ell.astype(np.float32)
    to_eye = np.asarray(eye, dtype=np.float64)[None, :] - X
    to_eye /= np.linalg.norm(to_eye, axis=1, keepdims=True)
    ell_view = lean_vector(to_eye, n, eta).astype(np.float32)  # (V, 3) at the receivers
    lobe = np.empty((len(p.i), 3), np.float32)
    kappa, lam = (np.ascontiguousarray(transport.lean[:, k], dtype=np.float32) for k in (0, 1))
    _lobes(p.i, p.d, p.r, ell, depth, kappa, lam, lobe)
    # Z_i: the source's lobe averaged over its receivers, weighted by the power each receives
    Z = np.empty((V, 3))
    _source_means(p.i, p.weight, lobe, p.spread, Z)
    T = [transport.matrices[min(c, len(transport.matrices) - 1)].tocsr() for c in range(3)]
    data = np.empty((3, len(p.i)), np.float32)
    N = p.N if exit else lobe  # (unread without the exit)
    _tilted(p.i, p.o, p.d, ell_view, kappa, N, exit, lobe, Z, T[0].data, T[1].data, T[2].data, data)
    mats = [sp.csr_matrix((data[c], T[c].indices, T[c].indptr), shape=T[c].shape) for c in range(3)]
    return dataclasses.replace(transport, matrices=mats)
