r"""Relighting: the radiance of every vertex under a light, from a prepared :class:`Transport`.

Per channel λ, the radiance leaving vertex o (W/(mm² sr)) for the irradiance E (W/mm²,
:mod:`.irradiance`) is

.. math:: L_\lambda = T_\lambda E \;+\; \mathrm{own}_\lambda \odot E \;+\;
          \alpha \odot W F_\lambda B_\lambda (s_\lambda E)

— the sparse near matrices, the measured own area and the far field (:mod:`.matrices` builds them) —
one sparse product per channel (:func:`relight_vertices`); :meth:`Transport.rows` keeps a few receivers'
rows and :meth:`Transport.coarse` sums the columns of cells for a draft.  The exitance :math:`\pi L`
leaves Lambertian, or behind a dielectric boundary with the angular shape of the transmission,
:math:`L(\theta_o) = M\, F_t(\theta_o) / (\pi (1 - F_{dr,e}))` (:func:`exit_fresnel`), or with the
incidence law's reciprocal exit (:func:`relight_object`).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numba import njit, prange
from scipy.spatial import cKDTree

from ..model.boundary import exit_factor
from ..model.incidence import incidence_law
from ._far_field import FarField
from .irradiance import vertex_irradiance
from .lean import Tilt, leaned


def view_cosines(mesh, viewpoint) -> np.ndarray:
    r""":math:`\cos\theta_o` per vertex: its normal against the direction to ``viewpoint`` (mm)."""
    to = np.asarray(viewpoint, dtype=np.float64) - np.asarray(mesh.vertices, dtype=np.float64)
    return np.einsum("vk,vk->v", to, np.asarray(mesh.vertex_normals)) / np.linalg.norm(to, axis=1)


def exit_fresnel(mesh, viewpoint, eta: float) -> np.ndarray:
    r"""Per-vertex factor :math:`F_t(\theta_o)/(1 - F_{dr,e})` toward ``viewpoint`` (1 where η = 1)."""
    if eta == 1.0:
        return np.ones(len(mesh.vertices))
    return exit_factor(view_cosines(mesh, viewpoint), eta)


@dataclass(kw_only=True)
class Transport:
    r"""The prepared transport: L_λ = T_λ E per channel (:func:`.transport.transport_matrices`).

    Either three matrices (one fall-off per channel) or one matrix T with the
    incident vertices' colour scale, :math:`T_\lambda = T\,\mathrm{diag}(s_\lambda)`; with a
    measured near field the own-area term is kept apart per channel:
    :math:`L_\lambda \mathrel{+}= \mathrm{own}_\lambda E`; the pairs beyond the near radius are the
    far field, :math:`L_\lambda \mathrel{+}= \alpha \odot W F_\lambda B_\lambda (s_\lambda E)`
    (:class:`translucency.transport._far_field.FarField`).
    """

    matrices: list  # CSR (V × V), float32: one or three
    scale: np.ndarray | None = None  # (V, 3) colour scale of the incident vertex (one matrix)
    own: np.ndarray | None = None  # (V, 3) A_i own_i / π: each vertex's own area, per channel (measured)
    far: FarField | None = None  # the pairs beyond the near radius (None: truncated, or none there)
    reflectance: np.ndarray | None = None  # (V, 3) measured normal-incidence total reflectance, blended
    through: bool = False  # the model's through-body table is in the matrices (model/through.py)
    lean: np.ndarray | None = None  # (V, 2, 3) κ and λ of the lean per vertex (model/lean.py), or None
    tilt: Tilt | None = None  # one light's lean on the near pairs (transport/lean.py: leaned), or None
    receivers: np.ndarray | None = None  # the vertices whose radiance it gives (None: all; :meth:`rows`)
    radius: float | None = None  # the near radius it was built at, mm (the far field takes the pairs beyond)

    def incidence(self, name: str = "half-space", eta: float = 1.0):
        """The incidence law ``name`` for this object (:func:`translucency.model.incidence.incidence_law`)."""
        return incidence_law(name, self.reflectance, eta)

    @functools.cached_property
    def one_pattern(self) -> bool:
        """Whether three matrices store the same pairs (checked once; :func:`relight_vertices` then reads
        them in one pass)."""
        return len(self.matrices) == 3 and _one_pattern(self.matrices)

    @property
    def nnz(self) -> int:
        """Stored pairs per channel."""
        return int(self.matrices[0].nnz)

    def coarse(self, vertices, receivers) -> Transport:
        r"""A draft between a few vertices: the irradiance is given at ``receivers`` only (indices into the
        mesh's ``vertices``, mm), each standing for the vertices nearest it (its cell); the radiance
        comes back at the receivers.  The columns of every cell are summed once,
        :math:`T'_{rj} = \sum_{i \in j} T_{ri}`, and a shared colour scale is taken per cell (its
        mean) — a coarser quadrature of the same transport, for a light that moves (the full one when
        it stops)."""
        r = np.asarray(receivers, dtype=np.int64)
        v = np.asarray(vertices, dtype=np.float64)
        _, cell = cKDTree(v[r]).query(v)
        P = sp.csr_matrix((np.ones(len(v), np.float32), (np.arange(len(v)), cell)), shape=(len(v), len(r)))
        scale = None
        if self.scale is not None:
            count = np.bincount(cell, minlength=len(r))[:, None]
            scale = (P.T @ self.scale.astype(np.float64) / np.maximum(count, 1)).astype(np.float32)
        sub = self.rows(r)  # the receivers' rows, then their columns summed per cell
        far = sub.far
        if far is not None:
            far = dataclasses.replace(far, B=[(B @ P).tocsr() for B in far.B])
        matrices = [(T @ P).tocsr() for T in sub.matrices]
        # (the lean is per pair of vertices: a draft between cells draws the paper's model)
        return dataclasses.replace(
            sub, matrices=matrices, scale=scale, far=far, receivers=None, lean=None, tilt=None
        )

    def rows(self, receivers) -> Transport:
        """The same transport giving the radiance of ``receivers`` (vertex indices) only: the rows of the
        near matrices and of the far field's interpolation (a relight of a few vertices under a light
        that lights them all)."""
        if self.tilt is not None:
            raise ValueError("Transport.rows: take the rows before the lean (leaned), not after")
        r = np.asarray(receivers, dtype=np.int64)
        far = None
        if self.far is not None:
            far = dataclasses.replace(
                self.far, W=self.far.W[r], alpha=self.far.alpha[r], label=self.far.label[r]
            )
        return dataclasses.replace(
            self,
            matrices=[T[r] for T in self.matrices],
            own=None if self.own is None else self.own[r],
            reflectance=None if self.reflectance is None else self.reflectance[r],
            far=far,
            receivers=r,
        )


@njit(parallel=True, cache=True)
def _csr_times_rgb(indptr, indices, data, X, out):
    """out = T X for a CSR matrix T and three columns X (V, 3): each row's pairs read once, rows on all
    cores."""
    for o in prange(indptr.shape[0] - 1):
        a0 = a1 = a2 = np.float32(0.0)
        for j in range(indptr[o], indptr[o + 1]):
            w, col = data[j], indices[j]
            a0 += w * X[col, 0]
            a1 += w * X[col, 1]
            a2 += w * X[col, 2]
        out[o, 0], out[o, 1], out[o, 2] = a0, a1, a2


@njit(parallel=True, cache=True)
def _csr3_times_rgb(indptr, indices, d0, d1, d2, X, out):
    """out[:, c] = T_c X[:, c] for three CSR matrices T_c on one pattern (``indptr``, ``indices``): each
    row's pairs read once for all three channels, rows on all cores."""
    for o in prange(indptr.shape[0] - 1):
        a0 = a1 = a2 = np.float32(0.0)
        for j in range(indptr[o], indptr[o + 1]):
            col = indices[j]
            a0 += d0[j] * X[col, 0]
            a1 += d1[j] * X[col, 1]
            a2 += d2[j] * X[col, 2]
        out[o, 0], out[o, 1], out[o, 2] = a0, a1, a2


def _one_pattern(matrices) -> bool:
    """Whether the three channels' CSR matrices store the same pairs (the fit's fall-off per channel on the
    pairs of one transport): then one pass over the pairs serves all three."""
    T0 = matrices[0]
    return all(
        T.indptr is T0.indptr
        or (np.array_equal(T.indptr, T0.indptr) and np.array_equal(T.indices, T0.indices))
        for T in matrices[1:]
    )


def relight_vertices(transport: Transport, E: np.ndarray) -> np.ndarray:
    """Radiance per vertex (V, 3) for irradiance E (V,) or (V, 3): one sparse product, plus the far field
    (per receiving vertex, (R, 3), for a transport restricted by :meth:`Transport.rows`).

    With one shared matrix the three channels go through it together (the matrix is read once,
    rows on all cores, Numba); so do three matrices on the same pairs (a fall-off per channel: the pairs
    read once, three values each); otherwise one SciPy product per channel.  A transport with one light's
    lean (``tilt``, :func:`translucency.transport.lean.leaned`) goes through its sources' pairs once, the
    lobes computed on the way (:meth:`~translucency.transport.lean.Tilt.apply`).  The far field (if
    prepared) adds two sparse products and one K × K product per channel.

    Examples
    --------
    >>> T = sp.csr_matrix(np.array([[0.5, 0.1], [0.1, 0.5]], dtype=np.float32))  # 2 vertices, 1/sr
    >>> transport = Transport(matrices=[T, T, 0.5 * T])  # blue: half of red and green
    >>> relight_vertices(transport, np.array([2.0, 0.0]))  # L = T E: the lit vertex, and its neighbour
    array([[1. , 1. , 0.5],
           [0.2, 0.2, 0.1]], dtype=float32)
    >>> own = Transport(matrices=[T, T, 0.5 * T], own=np.full((2, 3), 0.25, np.float32))
    >>> relight_vertices(own, np.array([2.0, 0.0]))  # + own E, each vertex its own irradiance
    array([[1.5, 1.5, 1. ],
           [0.2, 0.2, 0.1]], dtype=float32)
    """
    E = np.asarray(E, dtype=np.float32)
    E = np.repeat(E[:, None], 3, axis=1) if E.ndim == 1 else E
    rows = transport.matrices[0].shape[0]
    X = E if transport.scale is None else np.ascontiguousarray(E * transport.scale)
    if transport.tilt is not None:  # one light's lean, source by source (transport/lean.py)
        out = transport.tilt.apply(X, rows)
    elif len(transport.matrices) == 3 and transport.one_pattern:  # one matrix per channel, one set of pairs
        T, out = transport.matrices, np.empty((rows, 3), np.float32)
        _csr3_times_rgb(T[0].indptr, T[0].indices, T[0].data, T[1].data, T[2].data, X, out)
    elif len(transport.matrices) == 3:  # one matrix per channel, each its own pairs
        out = np.stack([T @ X[:, ch] for ch, T in enumerate(transport.matrices)], axis=1)
    else:
        T, out = transport.matrices[0], np.empty((rows, 3), np.float32)
        _csr_times_rgb(T.indptr, T.indices, T.data, X, out)
    if transport.own is not None:  # the receivers' own area: their own irradiance
        out += transport.own * (E if transport.receivers is None else E[transport.receivers])
    if transport.far is not None:  # the pairs beyond the near radius, through the clusters
        out += transport.far.apply(X)
    return out


def relight_object(
    transport: Transport,
    mesh,
    scene,
    light,
    viewpoint,
    *,
    eta: float = 1.0,
    incidence: str = "half-space",
    angles: bool = False,
    pairs=None,
):
    r"""What the camera at ``viewpoint`` sees of every vertex under ``light``: radiance (V, 3), W/(mm² sr).

    The whole chain once: the irradiance with shadows and the incidence law
    (:func:`vertex_irradiance`, :mod:`translucency.model.incidence`), the transport
    (:func:`relight_vertices`), the exit toward the camera — the boundary's Fresnel law
    (:func:`exit_fresnel`, η ≠ 1) or the incidence law's reciprocal exit (η = 1).  ``angles``: with a
    model that has a lean (:mod:`translucency.model.lean`), the near pairs lean toward the light's
    direction — its one direction per vertex, or its irradiance-weighted mean for light from many
    (:func:`translucency.transport.lean.leaned`); otherwise the paper's diffuse transport
    (:func:`translucency.transport.lean.lean_applies` says which is drawn); ``pairs``: the lean's pairs
    prepared once per transport (:func:`translucency.transport.lean.lean_pairs`), to keep them out of the
    per-light time; ``incidence``: a law's name (:data:`~translucency.model.incidence.INCIDENCE_LAWS`) or
    the law itself, prepared once (:class:`~translucency.transport.PreparedObject`).

    Returns
    -------
    L : ndarray, shape (V, 3)
    E : ndarray, shape (V,) or (V, 3)
        The (effective) irradiance.
    law : the incidence law used (its ``name`` goes into summaries).

    Examples
    --------
    >>> import translucency as tl
    >>> from translucency.render import object_of_model
    >>> model = tl.load_model(tl.data.example_path("spot_coarse.model.zip"))   # the example object
    >>> mesh, _ = object_of_model(model, {})
    >>> from translucency.mitsuba import mesh_scene
    >>> from translucency.render import Camera, parse_light
    >>> from translucency.transport.matrices import transport_matrices
    >>> from translucency.transport.relight import relight_object
    >>> T = transport_matrices(model, mesh)
    >>> light, camera = parse_light("point:60,-80,120,2e4"), Camera.looking_at(mesh)
    >>> L, E, law = relight_object(T, mesh, mesh_scene(mesh), light, camera.origin)
    >>> L.shape, law.name
    ((402, 3), 'half-space')
    """
    law = transport.incidence(incidence, eta) if isinstance(incidence, str) else incidence
    E = vertex_irradiance(mesh, scene, light, eta, law)
    tilted = leaned(transport, mesh, scene, light, viewpoint, eta=eta, pairs=pairs) if angles else None
    L = relight_vertices(tilted or transport, E) * exit_fresnel(mesh, viewpoint, eta)[:, None]
    exit_law = law.exit(view_cosines(mesh, viewpoint))
    return (L if exit_law is None else L * exit_law), E, law
