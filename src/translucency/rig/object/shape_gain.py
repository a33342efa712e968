r"""The scan's own shape in the near-peak model: how much brighter a photon walk on the mesh is than the
flat half-space's profile at the same material, cell by cell (a step of :mod:`.near_peak`).

The half-space's profile :math:`\sigma_t^2 f(\sigma_t r; \alpha)` (:mod:`translucency.model.half_space`)
assumes a flat surface.  On a convex part the surface falls away from its tangent plane by about
:math:`r^2 / 2\rho` (ρ the radius of curvature), into the light diffusing beneath: on a 15 mm ball in
skin1 the exits at 2–3 mm from the hit are 14–25 % brighter than the half-space's, at 4–6 mm 28–45 %.  A
ring fitted with the flat profile reads that excess as a shallower profile, and the peak comes out low
(0.5–0.7 of the tally's on two of three shots, docs/reference/object-rig.md, What the import does).

The gain of a cell v is the ratio of a photon walk on the mesh itself
(:func:`translucency.acquire.mesh_walk.mesh_random_walk`, index-matched, entering at the hit along the
inward normal, a homogeneous medium of the fitted σ_t and α) to the half-space's cell means, summed over
the cells within :math:`h_v = \max(\bar e_v / 2, \beta\, r_v)` of v (ē_v the mean length of v's own
edges, r_v the distance from the hit, β = :data:`NEIGHBOURHOOD`) on the same side of the surface
(normals within 60°: across a sheet thinner than h the far side is near too), so that a cell far from
the hit still holds enough exits and one at the hit is its own (a scan's cells are finest where its
detail is, a horn's tip: a neighbourhood of the mesh's mean edge there smooths the tip away):

.. math::  G_v = \frac{\sum_{|x_u - x_v| \le h_v} A_u R^{walk}_u}{\sum_{|x_u - x_v| \le h_v} A_u H_u},
   \qquad H_u = \frac{1}{A_u}\int \phi_u\, \sigma_t^2 f(\sigma_t |y - x_i|; \alpha)\, dA(y).

The near-peak model is then :math:`G_v(\sigma_t, \alpha) \cdot \sigma_t^2 f(\sigma_t r; \alpha)` on cell v,
fitted with the gains moving with the material (:class:`GainTable`: walks at a grid of σ_t and one
albedo, any albedo below it by reweighting each exit by its scatterings).  A profile unlike the
half-space's at the same material — a horn's tip, a sheet the light crosses unscattered — shows as a
gain far from 1, and is fitted as such.

Units: mm, R_d in mm⁻² per unit incident power.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...acquire.mesh import exit_barycentric
from ...acquire.mesh_walk import EXIT, mesh_random_walk
from ...acquire.volume import Volume
from ...model.half_space import half_space_R_d
from .quadrature import cell_quadrature

#: photons of each walk
PHOTONS = 50_000
#: the neighbourhood a gain is summed over, as a share of the cell's distance from the hit, and at least
#: this share of the cell's own mean edge (half: near the hit a cell's gain is its own)
NEIGHBOURHOOD = 0.3
OWN_EDGE = 0.5
#: a gain is kept within these bounds (a cell with no exit nearby is not made dark by the walk's noise;
#: a thin part's far side, where light crosses a sheet unscattered, may be a hundred times the flat's)
GAIN_RANGE = (0.02, 1000.0)
#: a neighbour counts towards a cell's gain where their normals agree this well (cos): the same side
SAME_SIDE = 0.5
#: the albedo of the walks a table reweights (any albedo up to it is reached), and their longest walk in
#: collisions (a photon still inside after it is dropped: its weight at albedo α ≤ 0.99 below 10⁻¹¹,
#: at 0.998 below 0.01 — the cost of the walks is mostly such photons' long paths)
WALK_ALBEDO = 0.999
MAX_STEPS = 3_000


def homogeneous_walk(mesh, scene, hit, normal, sigma_t: float, albedo: float, photons: int, *, seed: int,
                     eta: float = 1.0, max_steps: int = 200_000):  # fmt: skip
    """Photons from ``hit`` into ``mesh`` along −``normal``, in a homogeneous medium of σ_t (mm⁻¹) and albedo
    α behind a boundary of relative index ``eta`` (1: index-matched), light that leaves followed through
    the air into other parts (:func:`translucency.acquire.mesh_walk.mesh_random_walk`)."""
    volume = Volume.homogeneous(
        (1, 1, 1), float(np.max(mesh.extents)) + 1.0, [albedo * sigma_t] * 3, [(1 - albedo) * sigma_t] * 3,
        eta=eta,
    )  # fmt: skip
    entry, outward = np.asarray(hit, np.float64)[None], np.asarray(normal, np.float64)[None]
    return mesh_random_walk(
        scene, mesh.bounds, volume, 0, entry, outward, photons, seed=seed, index_matched=eta == 1.0,
        reentry=True, max_steps=max_steps,
    )  # fmt: skip


def mean_edge(mesh) -> np.ndarray:
    """Each vertex's own edges' mean length ē_v (V,), mm: a scan's cells are finest where its detail is."""
    ends, length = mesh.edges_unique.ravel(), np.repeat(mesh.edges_unique_length, 2)
    V = len(mesh.vertices)
    return np.bincount(ends, length, V) / np.maximum(np.bincount(ends, minlength=V), 1)


def same_side_pairs(mesh, centres: np.ndarray, candidates: np.ndarray, h: np.ndarray):
    """The pairs (i, j) with vertex ``candidates[j]`` within ``h[i]`` mm of vertex ``centres[i]`` and on the
    same side (normals within 60°, :data:`SAME_SIDE`: across a sheet thinner than h the far side's cells
    face away): two index arrays, into ``centres`` and into ``candidates``."""
    from scipy.spatial import cKDTree  # heavy: SciPy loads where a peak is recovered

    verts = np.asarray(mesh.vertices, dtype=np.float64)
    neighbours = cKDTree(verts[candidates]).query_ball_point(verts[centres], h)
    rows = np.repeat(np.arange(len(centres)), [len(n) for n in neighbours])
    cols = np.concatenate([np.asarray(n, dtype=np.int64) for n in neighbours])
    normals = np.asarray(mesh.vertex_normals, dtype=np.float64)
    side = np.einsum("ij,ij->i", normals[centres[rows]], normals[candidates[cols]]) > SAME_SIDE
    return rows[side], cols[side]


class MeshWalkGain:
    r"""The gains :math:`G_v` (module notes) of the cells within ``reach`` mm of one shot's hit.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The scan, mm.
    scene : mitsuba.Scene
        Its Mitsuba scene (:func:`translucency.mitsuba.mesh_scene`).
    hit : ndarray, shape (3,)
        Where the laser enters, mm.
    normal : ndarray, shape (3,)
        The outward unit normal there (the walk enters along −normal).
    seed : int
        The walks' seed (a shot's gains are a pure function of its arguments: a resumed import writes the
        same bytes).
    eta : float
        The boundary's relative index: 1 index-matched; > 1 the walks enter, reflect inside and leave
        with Fresnel's law, so that the gain against the (index-matched) half-space's profile holds the
        boundary's own effect too — the light it keeps inside and sends out further from the hit.

    Examples
    --------
    On a ball of 15 mm the walk is brighter than the flat profile away from the hit, and equal at it:

    >>> import numpy as np
    >>> import trimesh
    >>> from translucency.mitsuba import mesh_scene
    >>> from translucency.rig.object.shape_gain import MeshWalkGain
    >>> mesh = trimesh.creation.icosphere(4, radius=15.0)
    >>> shape = MeshWalkGain(mesh, mesh_scene(mesh), mesh.vertices[0], mesh.vertex_normals[0])
    >>> G = shape.gain([(1.0, 0.9)] * 3, reach=4.0)  # three walks, about 5 s  # doctest: +SKIP
    >>> r = np.linalg.norm(mesh.vertices - mesh.vertices[0], axis=1)
    >>> bool(abs(G[0, 0] - 1) < 0.05), bool(np.median(G[(r > 2) & (r < 4), 0]) > 1.05)  # doctest: +SKIP
    (True, True)
    """

    def __init__(self, mesh, scene, hit, normal, *, seed: int = 0, photons: int = PHOTONS, eta: float = 1.0):
        self.mesh, self.scene, self.eta = mesh, scene, float(eta)
        self.hit = np.asarray(hit, dtype=np.float64)
        self.normal = np.asarray(normal, dtype=np.float64) / np.linalg.norm(normal)
        self.seed, self.photons = seed, photons

    def gain(self, params, reach: float) -> np.ndarray:
        """(V, 3) gains: per channel, the walk at ``params[ch]`` = (σ_t mm⁻¹, α) against the half-space at
        the same; 1 beyond ``reach`` mm of the hit and in a channel whose params are None."""
        cells = _Cells(self.mesh, self.hit, reach)
        G = np.ones((len(self.mesh.vertices), 3))
        for ch, p in enumerate(params):
            if p is not None:
                sigma_t, albedo = (float(v) for v in p)
                walk = self._walk(sigma_t, albedo, self.seed + 7919 * ch, cells)
                G[cells.near, ch] = cells.gain(
                    walk.exits @ np.ones(walk.exits.shape[1]) / self.photons, sigma_t, albedo
                )
        return G

    def table(self, sigma_ts, reach: float, albedo_walk: float = WALK_ALBEDO) -> GainTable:
        """Walks at each of ``sigma_ts`` (mm⁻¹, ascending) and the albedo ``albedo_walk``: the gains at any
        (σ_t, α ≤ albedo_walk) between them (:class:`GainTable`)."""
        cells = _Cells(self.mesh, self.hit, reach)
        walks = [
            self._walk(float(st), albedo_walk, self.seed + 7919 * j, cells) for j, st in enumerate(sigma_ts)
        ]
        return GainTable(np.asarray(sigma_ts, dtype=np.float64), albedo_walk, walks, cells, self.photons)

    def _walk(self, sigma_t: float, albedo: float, seed: int, cells: _Cells) -> _Walk:
        """One walk from the hit in a homogeneous medium: each exit shared among the zone's cells by its
        barycentric weights (the tally's rule, :func:`~translucency.acquire.mesh.splat_exits`), and its
        scatterings."""
        import scipy.sparse as sp  # heavy: SciPy's sparse matrices load where a peak is recovered

        mesh = self.mesh
        walk = homogeneous_walk(
            mesh, self.scene, self.hit, self.normal, sigma_t, albedo, self.photons, seed=seed, eta=self.eta,
            max_steps=MAX_STEPS,
        )  # fmt: skip
        out = np.flatnonzero(walk.code == EXIT)
        tri, bary = exit_barycentric(mesh, walk.face[out], walk.position[out])
        row = cells.index[tri]  # each corner's row among the zone's cells (-1: outside)
        # the light that left unscattered (through a sheet thinner than the beam's free path) is a point:
        # kept apart, not spread over a neighbourhood (its cells' share exactly, and where it left)
        straight = walk.scatters[out] == 0
        row = np.where(straight[:, None], -1, row)
        inside = row >= 0
        col = np.repeat(np.arange(len(out)), 3).reshape(-1, 3)
        exits = sp.csr_matrix(
            (bary[inside], (row[inside], col[inside])), shape=(len(cells.zone), len(out))
        )  # zone cells × exits: Σ_exits gives N A_u R_u (scattered light)
        ballistic = np.zeros(len(mesh.vertices))
        np.add.at(ballistic, tri[straight].ravel(), bary[straight].ravel())
        point = walk.position[out][straight].mean(axis=0) if straight.any() else None
        return _Walk(exits, walk.scatters[out], walk.length[out], ballistic / self.photons, point)


class _Cells:
    """The cells within ``reach`` of the hit (``near``, whose gains are made), the wider ``zone`` their
    neighbourhoods reach, the zone's quadrature and the neighbourhood sums (a sparse near × zone)."""

    def __init__(self, mesh, hit, reach: float):
        import scipy.sparse as sp  # heavy: SciPy loads where a peak is recovered

        verts = np.asarray(mesh.vertices, dtype=np.float64)
        r = np.linalg.norm(verts - hit, axis=1)
        self.near = np.flatnonzero(r <= reach)
        h = np.maximum(OWN_EDGE * mean_edge(mesh)[self.near], NEIGHBOURHOOD * r[self.near])  # radius, mm
        self.zone = np.flatnonzero(r <= reach + h.max())  # every neighbourhood within it
        self.index = np.full(len(verts), -1)
        self.index[self.zone] = np.arange(len(self.zone))
        pts, self.w, self.owner = cell_quadrature(mesh, self.zone, toward=hit)
        self.dist = np.linalg.norm(pts - hit, axis=1)
        rows, cols = same_side_pairs(mesh, self.near, self.zone, h)
        self.S = sp.csr_matrix((np.ones(len(cols)), (rows, cols)), shape=(len(self.near), len(self.zone)))

    def gain(self, walked: np.ndarray, sigma_t: float, albedo: float) -> np.ndarray:
        """G over the near cells from the walk's A_u R_u (zone,) and the half-space's at (σ_t, α)."""
        flat = np.bincount(
            self.owner, self.w * half_space_R_d(self.dist, sigma_t, albedo), minlength=len(self.zone)
        )
        return np.clip((self.S @ walked) / np.maximum(self.S @ flat, 1e-300), *GAIN_RANGE)


@dataclass
class _Walk:
    exits: object  # sparse (zone cells, exits): each scattered exit's barycentric weights
    scatters: np.ndarray  # (exits,) real scatterings
    length: np.ndarray  # (exits,) path length inside, mm
    ballistic: np.ndarray  # (V,) A_v R_v of the light that left unscattered, per unit power
    point: np.ndarray | None  # where it left, mm (None: none did)


@dataclass
class GainTable:
    r"""Gains at any (σ_t, α) from walks at a grid of σ_t and one albedo α_w, by reweighting the walks'
    own paths.  A path that scattered k times and ran L mm inside has the density
    :math:`(\alpha\sigma_t)^k e^{-\sigma_t L}` (its other factors, the Fresnel reflections and
    refractions of a dielectric boundary, do not depend on the material), so a walk at
    (σ_j, α_w) counts at (σ_t, α) with the weight
    :math:`p/p_j = (\alpha/\alpha_w)^k (\sigma_t/\sigma_j)^k e^{-(\sigma_t - \sigma_j) L}`.  The two walks of
    the grid around σ_t are combined by the balance heuristic (a path of either walk weighs
    :math:`p / \tfrac12 (p_j + p_{j+1})`), so

    .. math::  A_u R_u = \frac{1}{2N} \sum_{j' \in \{j, j+1\}} \sum_{\text{exits of } j'}
       \phi_u \frac{p}{\tfrac12 (p_j + p_{j+1})} ,

    an unbiased estimate at every σ_t between the grid's, where interpolating the gains themselves is not:
    on a thin part the walk's tail and the half-space's fall with σ_t at different rates (an ear in skin1's
    blue, 3–6 mm from the hit: gains 1.45–2.2× a walk's at that σ_t, interpolated in log σ_t across a
    factor 2).  What :func:`.near_peak.recover_near_peak` fits with."""

    sigma_ts: np.ndarray
    albedo_walk: float
    walks: list
    cells: _Cells
    photons: int

    def ballistic(self, sigma_t: float) -> tuple[np.ndarray, np.ndarray | None]:
        r"""The unscattered light at σ_t: A_v R_v per cell (V,) and where it leaves (None: nowhere). Its
        power falls as :math:`e^{-\sigma_t L}` (L the sheet's thickness along the beam), so it is
        interpolated linearly in σ_t on a log scale; it does not depend on the albedo."""
        points = [w.point for w in self.walks if w.point is not None]
        if not points:
            return np.zeros_like(self.walks[0].ballistic), None
        s = float(np.clip(sigma_t, self.sigma_ts[0], self.sigma_ts[-1]))
        j = int(np.clip(np.searchsorted(self.sigma_ts, s) - 1, 0, len(self.sigma_ts) - 2))
        t = (s - self.sigma_ts[j]) / (self.sigma_ts[j + 1] - self.sigma_ts[j])
        a, b = self.walks[j].ballistic, self.walks[j + 1].ballistic
        both = (a > 0) & (b > 0)  # 0 where either walk had none there
        mixed = np.zeros_like(a)
        mixed[both] = np.exp((1 - t) * np.log(a[both]) + t * np.log(b[both]))
        return mixed, points[0]

    def __call__(self, sigma_t: float, albedo: float) -> np.ndarray:
        """(near,) gains of the cells within the reach at (σ_t mm⁻¹, α)."""
        s = float(np.clip(sigma_t, self.sigma_ts[0], self.sigma_ts[-1]))
        j = int(np.clip(np.searchsorted(self.sigma_ts, s) - 1, 0, len(self.sigma_ts) - 2))
        a = min(float(albedo), self.albedo_walk)
        walks, sigmas = self.walks[j : j + 2], self.sigma_ts[j : j + 2]  # the two walks around σ_t
        walked = np.zeros(self.cells.S.shape[1])  # A_u R_u over the zone's cells
        for walk in walks:
            k, L = walk.scatters, walk.length
            # log p_m / p for each walk m of the pair (the albedo's factor is the same for both)
            log_ratio = [k * np.log(sigma_m / s) - (sigma_m - s) * L for sigma_m in sigmas]
            log_mix = np.logaddexp(*log_ratio) - np.log(2.0)  # log ½ (p_j + p_{j+1}) / p
            weight = np.exp(k * (np.log(a) - np.log(self.albedo_walk)) - log_mix)
            walked += walk.exits @ weight / (2 * self.photons)
        return self.cells.gain(walked, s, a)


__all__ = ["MeshWalkGain", "GainTable", "PHOTONS", "homogeneous_walk", "mean_edge", "same_side_pairs"]
