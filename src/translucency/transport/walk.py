r"""The light that crosses the body, walked through the medium estimated from the scan.

Two parts make one picture (:class:`WalkedTransport`).  For a source vertex i and a receiving vertex o,
the pair is **near** when they are closer than the split radius :math:`R_s` (mm) and face the same way
(:math:`n_i \cdot n_o > 0`); every other pair is **crossed**:

- the near pairs are the measured model's, as the default draws them (the fitted profiles within
  :math:`R_s`, each vertex's own area and total as measured), each source's column carrying the share of
  its measured total that its profile puts within :math:`R_s` on the plane,
  :math:`f_i = \sum_k \frac{c_k}{d_k^2}\bigl(1 - (1 - d_k R_s) e^{d_k R_s}\bigr) / \sum_k \frac{c_k}{d_k^2}`;
- the crossed pairs are a walk of the light itself.  Photons enter where the light reaches the surface
  (each lit vertex by its share of the power :math:`E_j A_j`, W), **along the light's own direction**,
  walk through the estimated medium (:mod:`translucency.medium`, behind an index-matched boundary) and are
  tallied where they leave if their exit is crossed from their entry.  Toward a camera at ``eye`` each exit
  within ``cone_deg`` of the direction to it counts by its own direction,

  .. math:: L_o = \frac{1}{N} \sum_{\text{exits at } o \text{ in the cone}}
            \frac{\Phi\, \phi_o(y)}{A_o\, \pi \sin^2\!\gamma\, \cos\theta_o}
            \quad [\text{W}/(\text{mm}^2\,\text{sr})],

  (Φ the power a photon carries, :math:`\phi_o` the exit's barycentric weight, γ the cone's half-angle);
  without a camera (a scene's relight, the viewer) every exit counts as exitance,
  :math:`L_o = \frac{1}{N}\sum \Phi \phi_o / (\pi A_o)`.  The light that crossed a thin part unscattered is
  left out (a delta along the beam, seen only looking down it).

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
#: half-angle of the cone an exit is counted in toward the camera, degrees
CONE_DEG = 25.0
#: the width of the surface filter over the walk's tally, as a share of the split radius (the crossed light
#: varies over distances of the split radius and more; the tally's photon noise from vertex to vertex)
SMOOTH_SHARE = 0.5
#: the split radius, as the energy radius of the model's profiles (the share of a point's planar energy
#: within it)
SPLIT_SHARE = 0.9


@dataclass(frozen=True)
class WalkedTransport:
    """The measured near field from the model and the light that crosses the body walked through the
    estimated medium (module docstring)."""

    name: str = "walked"
    summary: str = "measured near field + the crossed light walked through the medium estimated from the scan"
    incidence: str = "half-space"
    split_share: float = SPLIT_SHARE
    photons: int = PHOTONS
    cone_deg: float = CONE_DEG
    smooth_share: float = SMOOTH_SHARE
    seed: int = 0

    def build(self, model, mesh, *, radius: float, shrink: bool, max_pairs: float):
        """What a renderer without a light's direction draws (a scene's relight, the viewer, the glTF
        bake: the irradiance alone, :meth:`PreparedObject.through`): the default's transport, the
        through-body table standing for the walk."""
        from ..medium import medium_of

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
        from .relight import relight_object

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
            cone_deg=self.cone_deg,
            smooth_mm=self.smooth_share * split,
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
    cone_deg: float = CONE_DEG, smooth_mm: float = 0.0, seed: int = 0,
) -> np.ndarray:  # fmt: skip
    """The radiance per vertex (V, 3), W/(mm² sr), of the light that crosses the body (module docstring):
    ``photons`` per channel from the lit vertices along the light, walked through ``volume``."""
    from ..acquire.mesh import exit_barycentric
    from ..acquire.mesh_walk import EXIT, mesh_random_walk

    X = np.asarray(mesh.vertices, dtype=np.float64)
    N = np.asarray(mesh.vertex_normals, dtype=np.float64)
    V = len(X)
    area = vertex_areas(mesh)
    E = vertex_irradiance(mesh, scene, light, eta)  # W/mm², shadowed, the entry's Fresnel against F_t(0)
    E = np.repeat(E[:, None], 3, axis=1) if E.ndim == 1 else E
    w_in = _arrival(light, scene, X, N)  # (V, 3) toward the light
    inward = np.where((np.einsum("vk,vk->v", w_in, N) > 1e-3)[:, None], -w_in, -N)
    rng = np.random.default_rng(seed)
    to_eye_v = None if eye is None else np.asarray(eye, dtype=np.float64)
    cos_c = np.cos(np.radians(cone_deg))
    face_n = np.asarray(mesh.face_normals, dtype=np.float64)
    L = np.zeros((V, 3))
    for ch in range(3):
        power = E[:, ch] * area  # W per vertex
        total = power.sum()
        if total <= 0:
            continue
        src = rng.choice(V, size=photons, p=power / total)  # each photon carries total / photons
        res = mesh_random_walk(
            scene, mesh.bounds, volume, ch, X[src], N[src], 1, seed=seed + 7919 * ch,
            index_matched=True, reentry=True, incoming=inward[src],
        )  # fmt: skip
        ok = np.flatnonzero((res.code == EXIT) & (res.scatters > 0))
        pos, face, j = res.position[ok].astype(np.float64), res.face[ok], src[ok]
        far = np.linalg.norm(pos - X[j], axis=1) >= split
        crossed = far | (np.einsum("nk,nk->n", N[j], face_n[face]) <= 0)  # the pairs the near part leaves
        pos, face, d = pos[crossed], face[crossed], res.direction[ok][crossed]
        weight = np.full(len(pos), total / photons / np.pi)  # exitance / π
        if to_eye_v is not None and eta == 1.0:  # by its own direction, toward the camera
            to_eye = to_eye_v - pos
            to_eye /= np.linalg.norm(to_eye, axis=1, keepdims=True)
            d = d / np.linalg.norm(d, axis=1, keepdims=True)
            cos_o = np.maximum(np.einsum("nk,nk->n", face_n[face], to_eye), 0.1)
            inside = np.einsum("nk,nk->n", d, to_eye) > cos_c
            weight = np.where(inside, total / photons / ((1.0 - cos_c**2) * np.pi * cos_o), 0.0)
        tri, bary = exit_barycentric(mesh, face, pos)
        L[:, ch] = np.bincount(tri.ravel(), (bary * weight[:, None]).ravel(), V) / area
    if smooth_mm > 0:
        L = surface_filter(mesh, smooth_mm) @ L
    if eye is not None and eta != 1.0:
        L *= exit_fresnel(mesh, eye, eta)[:, None]
    return L


def surface_filter(mesh, h: float):
    r"""The (V × V) CSR filter :math:`S_{oq} \propto A_q\, e^{-|x_o - x_q|^2 / 2h^2}` over the vertices q
    within 2h of o that face its way (:math:`n_o \cdot n_q > 1/2`: a thin part's two sides stay apart), each
    row summing to 1 (h in mm)."""
    X = np.asarray(mesh.vertices, dtype=np.float64)
    N = np.asarray(mesh.vertex_normals, dtype=np.float64)
    V = len(X)
    pairs = cKDTree(X).query_pairs(2.0 * h, output_type="ndarray")
    o = np.concatenate([pairs[:, 0], pairs[:, 1], np.arange(V)])
    q = np.concatenate([pairs[:, 1], pairs[:, 0], np.arange(V)])
    keep = np.einsum("mk,mk->m", N[o], N[q]) > 0.5
    o, q = o[keep], q[keep]
    w = vertex_areas(mesh)[q] * np.exp(-np.sum((X[o] - X[q]) ** 2, axis=1) / (2 * h * h))
    S = sp.csr_matrix((w, (o, q)), shape=(V, V))
    return sp.diags(1.0 / np.asarray(S.sum(axis=1)).ravel()) @ S


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
