r"""The light that crosses the body, walked through the medium estimated from the scan.

Two parts make one picture (:class:`WalkedTransport`).  For a source vertex i and a receiving vertex o,
the pair is **near** when they are closer than the split radius :math:`R_s` (mm) and face the same way
(:math:`n_i \cdot n_o > 0`); every other pair is **crossed**:

- the near pairs are the measured model's, as the default draws them (the fitted profiles within
  :math:`R_s`, each vertex's own area and total as measured), each source's column carrying the share of
  its measured total that its profile puts within :math:`R_s` on the plane,
  :math:`f_i = \sum_k \frac{c_k}{d_k^2}\bigl(1 - (1 - d_k R_s) e^{d_k R_s}\bigr) / \sum_k \frac{c_k}{d_k^2}`;
- the crossed pairs are a walk of the light itself.  Photons enter where the light reaches the surface
  (drawn by the lit vertices' mean power over the channels :math:`E_j A_j`, W, each carrying its channel's
  share), **along the light's own direction**, walk through the estimated medium (:mod:`translucency.medium`,
  behind an index-matched boundary; the three channels with the same random numbers) and are tallied where
  they leave if their exit is crossed from their entry.  Toward a camera at ``eye`` each exit counts by its
  own direction d, spread over a normalised lobe about the direction e to the camera,

  .. math:: \mathrm{splat}_o = \sum_{\text{exits}} \Phi\, \phi_o(y)\,
            \frac{n + 1}{2\pi} \frac{(d \cdot e)_+^n}{\cos\theta_o} \quad [\text{W/sr}],

  (Φ the power a photon carries, :math:`\phi_o` the exit's barycentric weight); without a camera (every
  exit as exitance) :math:`\mathrm{splat}_o = \sum \Phi \phi_o / \pi`.  The radiance is a photon map's
  density estimate over the surface, :math:`L_o = \sum_q k_q \mathrm{splat}_q / \sum_q k_q A_q`
  (:func:`_gathered`, W/(mm² sr)).  The light that crossed a thin part unscattered is left out (a delta
  along the beam, seen only looking down it).

The split makes the two parts complementary: no pair is in both, and each pair is in one.  Behind a
dielectric boundary (η ≠ 1) the walk's power holds the entry's :math:`F_t(\theta_i)/F_t(0)` and its exits
the exit factor of every transport (:func:`~translucency.transport.relight.exit_fresnel`), counted as
exitance (the directions inside are not those outside).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .._validate import TranslucencyError
from ..geometry import vertex_areas
from .irradiance import vertex_irradiance
from .matrices import transport_matrices
from .parameters import neighbour_weights, vertex_parameters
from .relight import exit_fresnel

#: photons per channel a light's walk sends
PHOTONS = 400_000
#: the exponent of the lobe an exit's direction is spread over toward the camera (:func:`_lobe`)
LOBE = 8.0
#: the exits a vertex's radiance gathers (:func:`_gathered`): its photon noise about 1/√GATHER
GATHER = 256
#: the nearest vertices a vertex gathers from, at most
GATHER_VERTICES = 160
#: the split radius, as the energy radius of the model's profiles (the share of a point's planar energy
#: within it)
SPLIT_SHARE = 0.6


@dataclass(frozen=True)
class WalkedTransport:
    """The measured near field from the model and the light that crosses the body walked through the
    estimated medium (module docstring)."""

    name: str = "walked"
    summary: str = "measured near field + the crossed light walked through the medium estimated from the scan"
    incidence: str = "half-space"
    split_share: float = SPLIT_SHARE
    photons: int = PHOTONS
    lobe: float = LOBE
    gather: int = GATHER
    seed: int = 0

    def build(self, model, mesh, *, radius: float, shrink: bool, max_pairs: float):
        """What a renderer without a light's direction draws (a scene's relight, the viewer, the glTF
        bake: the irradiance alone, :meth:`PreparedObject.through`): the default's transport, the
        through-body table standing for the walk."""
        from ..medium import medium_of  # (the medium's module loads with the walk's kind only)

        if medium_of(model) is None:
            raise TranslucencyError(
                "transport walked: the model holds no estimated medium (fit it again with this version)"
            )
        return transport_matrices(model, mesh, radius=radius, shrink=shrink, max_pairs=max_pairs)

    def near(self, prepared):
        """The near part (once per object): :func:`~.matrices.transport_matrices` truncated at the split
        radius, without the through-body table, each column the share of its total within the split, the
        opposite side left to the walk."""
        cached = prepared.__dict__.get("_walk_near")
        if cached is None:
            model, mesh = prepared.model, prepared.mesh
            split = min(_split_radius(model, self.split_share), prepared.radius)
            T = transport_matrices(
                model, mesh, radius=split, max_pairs=prepared.options.max_pairs, through=False,
                far_field=False,
            )  # fmt: skip
            cached = prepared.__dict__["_walk_near"] = _near_part(T, model, mesh, split)
        return cached

    def relight(self, prepared, light, eye, scene):
        """The radiance toward ``eye`` (V, 3) and the irradiance E: the near part as every transport draws
        it, plus the walk of the crossed light."""
        from .relight import relight_object  # relight imports the kinds' module: a cycle at load

        near = self.near(prepared)
        law = prepared.law
        L, E, _ = relight_object(near, prepared.mesh, scene, light, eye, eta=prepared.eta, incidence=law)
        return L + self.walk(prepared, light, eye, scene, split=near.radius), E

    def walk(self, prepared, light, eye, scene, *, split: float) -> np.ndarray:
        """The crossed part alone: radiance per vertex (V, 3), W/(mm² sr)."""
        return walk_crossed(
            prepared.mesh,
            prepared.medium_volume,
            light,
            scene,
            split=split,
            eye=eye,
            eta=prepared.eta,
            photons=self.photons,
            lobe=self.lobe,
            gather=self.gather,
            seed=self.seed,
        )


def _split_radius(model, share: float) -> float:
    """The split radius R_s (mm): the largest over points and channels of the radius holding ``share`` of
    the profile's planar energy."""
    return float(np.max(model.energy_radius(share)))


def _near_part(T, model, mesh, split: float):
    """``T`` (truncated at ``split``) with the opposite side's pairs removed and each column scaled to its
    profile's share within ``split``."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    area = vertex_areas(mesh)
    c, d, _ = vertex_parameters(model, mesh, weights=neighbour_weights(model, mesh))
    share = _planar_share(c, d, split)  # (V, C)
    mats = []
    for ch, M in enumerate(T.matrices):
        M = M.tocoo()
        same = np.einsum("mk,mk->m", n[M.row], n[M.col]) > 0
        before = np.bincount(M.col, area[M.row] * M.data, len(v))
        after = np.bincount(M.col[same], area[M.row[same]] * M.data[same], len(v))
        keep = np.divide(before, after, out=np.ones(len(v)), where=after > 0)
        f = share[:, min(ch, share.shape[1] - 1)] * keep
        vals = (M.data[same] * f[M.col[same]]).astype(np.float32)
        mats.append(sp.csr_matrix((vals, (M.row[same], M.col[same])), shape=M.shape))
    return dataclasses.replace(T, matrices=mats, far=None, through=False, radius=split)


def _planar_share(c: np.ndarray, d: np.ndarray, R: float) -> np.ndarray:
    r"""Per vertex and channel, the share of :math:`\int_0^\infty 2\pi r \sum_k c_k e^{d_k r} dr` within R
    (d_k < 0, mm⁻¹): :math:`\sum_k c_k d_k^{-2} (1 - (1 - d_k R) e^{d_k R}) / \sum_k c_k d_k^{-2}`."""
    whole = c / d**2
    inside = whole * (1.0 - (1.0 - d * R) * np.exp(d * R))
    return np.clip(inside.sum(axis=-1) / np.maximum(whole.sum(axis=-1), 1e-300), 0.0, 1.0)


def walk_crossed(
    mesh, volume, light, scene, *, split: float, eye=None, eta: float = 1.0, photons: int = PHOTONS,
    lobe: float = LOBE, gather: int = GATHER, seed: int = 0,
) -> np.ndarray:  # fmt: skip
    r"""The radiance per vertex (V, 3), W/(mm² sr), of the light that crosses the body (module docstring):
    ``photons`` from the lit vertices along the light, walked through ``volume`` in each channel with the
    same random numbers (the channels' noise is alike: it shows as brightness, not as colour); each vertex
    gathers ``gather`` exits (:func:`_gathered`; 0: its own tally alone, :math:`\mathrm{splat}_o / A_o`)."""
    from ..medium import walk_beams  # the walk loads Mitsuba: only where a light is walked

    X = np.asarray(mesh.vertices, dtype=np.float64)
    N = np.asarray(mesh.vertex_normals, dtype=np.float64)
    V = len(X)
    area = vertex_areas(mesh)
    E = vertex_irradiance(mesh, scene, light, eta)  # W/mm², shadowed, the entry's Fresnel against F_t(0)
    E = np.repeat(E[:, None], 3, axis=1) if E.ndim == 1 else E
    power = E * area[:, None]  # (V, 3) W per vertex
    mean = power.mean(axis=1)
    if mean.sum() <= 0:
        return np.zeros((V, 3))
    w_in = _arrival(light, scene, X, N)  # (V, 3) toward the light
    inward = np.where((np.einsum("vk,vk->v", w_in, N) > 1e-3)[:, None], -w_in, -N)
    # the entries, drawn by the channels' mean power; each photon carries power_c / (photons p) in channel c
    p = mean / mean.sum()
    src = np.random.default_rng(seed).choice(V, size=photons, p=p)
    carried = power[src] / (photons * p[src, None])  # (photons, 3) W
    face_n = np.asarray(mesh.face_normals, dtype=np.float64)
    splat, count = np.zeros((V, 3)), np.zeros((V, 3))
    for ch in range(3):
        out = walk_beams(mesh, volume, ch, X[src], N[src], incoming=inward[src], seed=seed, scene=scene)
        j = src[out.beam]
        far = np.linalg.norm(out.position - X[j], axis=1) >= split
        crossed = far | (np.einsum("nk,nk->n", N[j], face_n[out.face]) <= 0)  # the pairs the near part leaves
        pos, face, d = out.position[crossed], out.face[crossed], out.direction[crossed]
        tri, bary, power_c = out.tri[crossed], out.bary[crossed], carried[j[crossed], ch]
        radiance = power_c / np.pi  # as exitance: Φ / π per unit area
        if eye is not None and eta == 1.0:  # by its own direction, toward the camera
            radiance = power_c * _lobe(d, np.asarray(eye, dtype=np.float64) - pos, face_n[face], lobe)
        splat[:, ch] = np.bincount(tri.ravel(), (bary * radiance[:, None]).ravel(), V)
        count[:, ch] = np.bincount(tri.ravel(), bary.ravel(), V)
    L = _gathered(mesh, splat, count.mean(axis=1), gather) if gather > 0 else splat / area[:, None]
    if eye is not None and eta != 1.0:
        L *= exit_fresnel(mesh, eye, eta)[:, None]
    return L


def _lobe(d, to_eye, m, n: float) -> np.ndarray:
    r"""Each exit's radiance toward the eye per unit of its power and of area (sr⁻¹): its direction d spread
    over the normalised lobe :math:`K = \frac{n + 1}{2\pi} (d \cdot e)^n` about the direction e to the eye,
    over the exit face's :math:`\cos\theta_o = m \cdot e` (at least 0.1)."""
    e = to_eye / np.linalg.norm(to_eye, axis=1, keepdims=True)
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    cos_o = np.maximum(np.einsum("nk,nk->n", m, e), 0.1)
    return (n + 1) / (2 * np.pi) * np.maximum(np.einsum("nk,nk->n", d, e), 0.0) ** n / cos_o


def _gathered(mesh, splat: np.ndarray, count: np.ndarray, gather: int) -> np.ndarray:
    r"""The radiance per vertex from the exits splatted to the vertices (``splat`` (V, 3) W/sr, ``count``
    (V,) exits): at each vertex o, over its ``GATHER_VERTICES`` nearest vertices q that face its way,
    :math:`L_o = \sum_q k_q\, \mathrm{splat}_q / \sum_q k_q A_q` with the Epanechnikov weight
    :math:`k_q = 1 - |x_o - x_q|^2 / h_o^2` — the exits over the surface they fell on — and :math:`h_o` the
    distance within which ``gather`` exits fell (a photon map's density estimate: wide where few exits
    fell, down to the vertex spacing where many did)."""
    X = np.asarray(mesh.vertices, dtype=np.float64)
    N = np.asarray(mesh.vertex_normals, dtype=np.float64)
    area = vertex_areas(mesh)
    M = min(GATHER_VERTICES, len(X))
    dist, nb = cKDTree(X).query(X, k=M)
    facing = np.einsum("vk,vmk->vm", N, N[nb]) > 0.5
    reached = np.cumsum(count[nb] * facing, axis=1) >= gather
    first = np.where(reached.any(axis=1), reached.argmax(axis=1), M - 1)
    h = np.maximum(dist[np.arange(len(X)), first], np.sqrt(area))[:, None] * 1.0001
    k = np.maximum(1.0 - (dist / h) ** 2, 0.0) * facing
    return np.einsum("vm,vmc->vc", k, splat[nb]) / np.einsum("vm,vm->v", k, area[nb])[:, None]


def _arrival(light, scene, X, N) -> np.ndarray:
    """The direction toward the light at each vertex (V, 3); a light without one direction (a sky): the
    normal (the beams then enter straight in)."""
    arrival = getattr(light, "arrival", None)
    if arrival is None:
        return N
    try:
        w = np.asarray(arrival(scene, X, N)[0], dtype=np.float64)
    except (NotImplementedError, AttributeError, TypeError):
        return N
    return np.broadcast_to(w, X.shape)
