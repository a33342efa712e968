r"""Precomputed radiance transfer: every vertex's response to a small light basis, shadows and subsurface
transport included (Sloan, Kautz and Snyder 2002, who carried it through subsurface transfer too).

A distant light of radiance :math:`L(\omega)` (W/(mm² sr)) gives vertex i the effective irradiance

.. math:: E_i = \int L(\omega)\, V_i(\omega)\, \cos^+\theta_i\, F_i(\cos\theta_i)\,
          \frac{F_t(\theta_i)}{F_t(0)}\, d\omega

(visibility :math:`V_i`, the incidence law :math:`F_i` per channel and, behind a dielectric boundary,
the Fresnel ratio: :func:`translucency.transport.irradiance.vertex_irradiance`), and the transport
(:func:`~translucency.transport.relight.relight_vertices`, linear in E) turns it into the radiance
:math:`B_o = (T E)_o` (Lambertian exit, before the exit law).  With the light in real spherical
harmonics, :math:`L \approx \sum_k L_k Y_k` (:mod:`.sh`, :meth:`.lights.Light.sh_coefficients`),
everything is linear:

.. math:: B_o \approx \sum_k L_k\, t_{o,k}, \qquad t_{o,k} = \bigl(T\, E^{(k)}\bigr)_o, \qquad
          E^{(k)}_i = \frac{4\pi}{S} \sum_{s} Y_k(\omega_s)\, V_i(\omega_s)\, \cos^+\theta_{is}\,
          F_i(\cos\theta_{is})\, \frac{F_t(\theta_{is})}{F_t(0)},

the sum over S directions of a Fibonacci lattice.  Relighting is then K products per vertex and
channel — the page does it in its shader for any direction and turn of the light.

**Sharp lights.**  The basis is band-limited: a directional light's clamped cosine and shadow edge
would be blurred over about π / bands radians and ring.  Most of a vertex's response to it is local,
:math:`a_o E_o` with :math:`a_o = \sum_i T_{oi}` (its response to an irradiance uniform around it),
so only the rest goes through the basis and the local part is evaluated exactly:

.. math:: B_o \approx \sum_k L_k \bigl(t_{o,k} - a_o \bar E^{(k)}_o\bigr) + a_o E_o(\omega_l),

with :math:`\bar E^{(k)}` the channels' mean of :math:`E^{(k)}` and :math:`E_o(\omega_l)` the vertex's
own irradiance with its shadow (the page: a shadow map) — :meth:`Transfer.radiance` with
``local_irradiance``.  The error against the full relight is stated by
:func:`translucency.view.object_page.transfer_errors`.

**The lean** (``angles``, a model with one: :mod:`translucency.model.lean`).  The transport then depends
on the direction the light comes from — T(ω), each near pair tilted toward ω (:func:`.lean.tilted`) — but
the radiance is still linear in L, so the transfer keeps its form with the tilt inside the integral:

.. math:: t_{o,k} = \frac{4\pi}{S} \sum_s Y_k(\omega_s) \bigl(T(\omega_s)\, w(\omega_s)\bigr)_o,

:math:`w_i(\omega_s)` the lattice direction's own weight above (visibility, cosine, law): one tilted
relight per direction of the lattice (S of them, not K) — the page is unchanged, and it draws the lean of
every light and sky it is turned to, the directions' lobes themselves rather than the lobe of their mean
(:func:`.lean.light_lean`'s approximation for a sky).  The local part :math:`a_o` stays the paper's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..mitsuba import rays
from ..model.boundary import fresnel_transmittance
from ..model.lean import lean_vector
from . import sh
from .lean import lean_pairs, tilted
from .relight import Transport, relight_vertices

#: bands of the light basis by default: 16 coefficients per vertex and channel
DEFAULT_BANDS = 4
#: directions of the lattice the basis is projected with (visibility rays per vertex: about half)
DEFAULT_DIRECTIONS = 256
#: rays traced at once (memory: about 60 bytes a ray)
_RAYS_PER_BATCH = 1 << 22


@dataclass(frozen=True, kw_only=True)
class Transfer:
    r"""Each vertex's transfer vector: radiance (V, K, 3) per unit coefficient of the light basis.

    ``coefficients[o, k, c]`` is :math:`t_{o,k}` of channel c, W/(mm² sr) of radiance per W/(mm² sr) of
    the basis function :math:`Y_k`'s weight; ``irradiance[o, k]``: :math:`\bar E^{(k)}_o`, the vertex's own
    irradiance per unit weight (mean of the channels); ``local[o, c]``: :math:`a_o = \sum_i T_{oi}`, sr⁻¹;
    ``bands``: K = bands².
    """

    coefficients: np.ndarray
    irradiance: np.ndarray
    local: np.ndarray
    bands: int
    directions: int

    def radiance(self, light_coefficients: np.ndarray, local_irradiance=None) -> np.ndarray:
        r""":math:`B_o = \sum_k L_k t_{o,k}` (V, 3) for a light's coefficients (K, 3); with the light's
        exact ``local_irradiance`` :math:`E_o` (V,) or (V, 3) the local part is taken exactly (module
        docstring: sharp lights)."""
        L = np.asarray(light_coefficients, np.float64)
        B = np.einsum("vkc,kc->vc", self.coefficients, L)
        if local_irradiance is not None:
            E = np.asarray(local_irradiance, np.float64)
            E = E[:, None] if E.ndim == 1 else E
            B += self.local * (E - np.einsum("vk,kc->vc", self.irradiance, L))
        return B


def transfer_vectors(
    transport: Transport,
    mesh,
    scene,
    law,
    *,
    bands: int = DEFAULT_BANDS,
    directions: int = DEFAULT_DIRECTIONS,
    eta: float = 1.0,
    angles: bool = False,
    progress=None,
) -> Transfer:
    """The transfer of every vertex of ``mesh`` (module docstring): K irradiances with shadows, then
    K relights through ``transport`` — or, with ``angles`` and a transport with a lean, one tilted relight
    per direction of the lattice (module docstring: the lean).

    ``scene``: the object's Mitsuba scene for the shadow rays (:func:`translucency.mitsuba.mesh_scene`);
    ``law``: the incidence law (``transport.incidence(...)``); ``progress(done, total)`` after each batch.
    """
    v = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    V, K = len(v), sh.n_coefficients(bands)
    omega = sh.sphere_directions(directions)
    Y = sh.basis(omega, bands)  # (S, K)
    eps = 5e-4 * float(np.max(mesh.extents))
    origin = v + n * eps
    E = np.zeros((V, 3, K))
    lean = angles and transport.lean is not None
    pairs = lean_pairs(transport, mesh, eta) if lean else None
    t = np.zeros((V, K, 3)) if lean else None  # with the lean: Σ_s Y_k(ω_s) T(ω_s) w(ω_s), by direction
    per_batch = max(1, _RAYS_PER_BATCH // V)
    for s0 in range(0, directions, per_batch):
        s = slice(s0, min(s0 + per_batch, directions))
        cos_i = n @ omega[s].T  # (V, b)
        vi, si = np.nonzero(cos_i > 0)  # only the directions above each vertex's tangent plane
        blocked = np.asarray(scene.ray_test(rays(origin[vi], omega[s][si])))
        cos_vs = cos_i[vi, si]
        weight = np.where(blocked, 0.0, cos_vs)  # V cos⁺, then the boundary's ratio and the law
        if eta != 1.0:
            weight *= fresnel_transmittance(cos_vs, eta) / fresnel_transmittance(1.0, eta)
        w3 = np.zeros(cos_i.shape + (3,))
        F = law.factor(cos_i)  # (V, b, 3) or None
        w3[vi, si] = weight[:, None] * (1.0 if F is None else F[vi, si])
        E += np.matmul(w3.transpose(0, 2, 1), Y[s]) * (4.0 * math.pi / directions)  # (V, 3, K)
        if lean:  # T(ω_s) w(ω_s) for each direction of the batch, ω_s toward the light
            for b, d in enumerate(range(s.start, s.stop)):
                ell = lean_vector(np.broadcast_to(omega[d], n.shape), n, eta)
                L_s = relight_vertices(tilted(transport, mesh, ell, eta=eta, pairs=pairs), w3[:, b, :])
                t += L_s[:, None, :] * Y[d][None, :, None] * (4.0 * math.pi / directions)
        if progress:
            progress(s.stop, directions)
    E = E.transpose(0, 2, 1)  # (V, K, 3)
    if not lean:  # the paper's transport is one matrix for every direction: T Σ_s = Σ_s T
        t = np.stack([relight_vertices(transport, E[:, k, :]) for k in range(K)], axis=1)
    local = relight_vertices(transport, np.ones(V))  # a_o: the response to a uniform irradiance
    return Transfer(
        coefficients=t.astype(np.float32),
        irradiance=E.mean(axis=2).astype(np.float32),
        local=np.asarray(local, np.float32),
        bands=bands,
        directions=directions,
    )
