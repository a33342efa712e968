r"""The lean in the renderer: the near transport tilted toward the light's and the camera's directions
(:mod:`translucency.model.lean`).

For a light of one direction per vertex (directional, point, spot: ``light.arrival``) and a camera at
``eye``, every near pair (o, i) of the prepared transport (:mod:`.transport`) is weighted per channel by

.. math:: T'_{oi} = T_{oi}\,
          \frac{e^{\kappa_i \vec\ell_i \cdot \hat d_{oi}}}{Z_i}\,
          \frac{e^{-\kappa_o \vec\ell'_o \cdot \hat d_{oi}}}{N_{oi}}, \qquad
          Z_i = \frac{\sum_o A_o T_{oi} e^{\kappa_i \vec\ell_i \cdot \hat d_{oi}}}{\sum_o A_o T_{oi}},

with :math:`\hat d_{oi}` the unit vector from :math:`x_i` to :math:`x_o`, :math:`\vec\ell_i` the lean
vector of the light at the source and :math:`\vec\ell'_o` that of the direction to the camera at the
receiver, κ blended to every vertex from the fitted points.  Each source still sends its measured total
(the near pairs' share of it: the far field and the own area are left diffuse), and each pair's exit
averages to its diffuse value over the hemisphere.  A light of many directions (an environment map) has
no one lean vector: it draws the paper's model (:func:`leaned` returns None and says why).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp

from ..geometry import vertex_areas
from ..model.lean import exit_normalisation, lean_vector

#: pairs handled at once (about 400 bytes each in flight)
_PAIRS_PER_BATCH = 1 << 21


def lean_pairs(transport, mesh, eta: float = 1.0):
    r"""What the lean needs of the transport's near pairs, light- and camera-independent: (o, i, d, N),
    the rows and columns (nnz,), the unit vectors :math:`\hat d_{oi}` (nnz, 3) float32 (0 on the diagonal)
    and the exit normalisation :math:`N_{oi}` (nnz, 3) float32."""
    T = transport.matrices[0].tocsr()
    o = np.repeat(np.arange(T.shape[0]), np.diff(T.indptr))
    i = T.indices.astype(np.int64)
    X = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    if transport.receivers is not None:
        o = np.asarray(transport.receivers)[o]
    kappa = transport.lean.astype(np.float64)
    d = np.zeros((len(o), 3), np.float32)
    N = np.ones((len(o), 3), np.float32)
    for s in range(0, len(o), _PAIRS_PER_BATCH):
        oo, ii = o[s : s + _PAIRS_PER_BATCH], i[s : s + _PAIRS_PER_BATCH]
        v = X[oo] - X[ii]
        r = np.linalg.norm(v, axis=1, keepdims=True)
        dd = np.divide(v, r, out=np.zeros_like(v), where=r > 0)
        d[s : s + len(oo)] = dd
        N[s : s + len(oo)] = exit_normalisation(kappa[oo], -dd, n[oo], eta)
    return o, i, d, N


def lean_applies(transport, light) -> bool:
    """Whether :func:`leaned` tilts this transport for this light: the model has a lean and the light
    one direction per vertex."""
    return transport.lean is not None and bool(getattr(light, "delta", False))


def leaned(transport, mesh, scene, light, eye, *, eta: float = 1.0, exit: bool = True, pairs=None):
    """The transport with the lean of ``light`` and the camera at ``eye`` (mm), or None where it does not
    apply (no κ in the model, or a light of many directions).

    Parameters
    ----------
    transport : Transport
        Prepared by :func:`~translucency.render.transport.transport_matrices` from a model with a lean
        (``transport.lean``, κ (V, 3)).
    mesh, scene
        The object and its Mitsuba scene.
    light : Light
        A light with ``arrival`` (directional, point, spot).
    eye : array_like, shape (3,)
        The camera's position, mm.
    eta : float
        Relative index of the boundary (1: index-matched).
    exit : bool
        Also the exit's lean (False: the light's only — the ablation).
    pairs : tuple, optional
        :func:`lean_pairs`' result, to reuse between lights.

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
    o, i, d, N = lean_pairs(transport, mesh, eta) if pairs is None else pairs
    X = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    V = len(X)
    area = vertex_areas(mesh)
    kappa = transport.lean.astype(np.float64)
    w_light = light.arrival(scene, X, n)[0]
    ell = lean_vector(w_light, n, eta)  # (V, 3) at the sources
    to_eye = np.asarray(eye, dtype=np.float64)[None, :] - X
    to_eye /= np.linalg.norm(to_eye, axis=1, keepdims=True)
    ell_view = lean_vector(to_eye, n, eta)  # (V, 3) at the receivers
    a = np.einsum("mk,mk->m", d, ell[i]).astype(np.float32)  # the incidence lean's argument per pair
    b = -np.einsum("mk,mk->m", d, ell_view[o]).astype(np.float32)  # the exit lean's
    off = np.any(d != 0, axis=1)
    mats = []
    for c in range(3):
        T = transport.matrices[min(c, len(transport.matrices) - 1)].tocsr()
        vals = T.data.astype(np.float64)
        if transport.scale is not None:  # the shared-colour model: Z weighs with its scale too
            vals = vals * transport.scale[i, c]
        lobe = np.where(off, np.exp(kappa[i, c] * a), 1.0)
        weight = area[o] * vals * off
        Z = np.bincount(i, weight * lobe, minlength=V)
        Z = np.divide(Z, np.bincount(i, weight, minlength=V), out=np.ones(V), where=Z > 0)
        exit_lobe = np.where(off, np.exp(kappa[o, c] * b) / N[:, c], 1.0) if exit else 1.0
        data = T.data * np.where(off, lobe / Z[i], 1.0) * exit_lobe
        mats.append(sp.csr_matrix((data.astype(np.float32), T.indices, T.indptr), shape=T.shape))
    return dataclasses.replace(transport, matrices=mats)
