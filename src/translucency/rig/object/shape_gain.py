r"""The scan's own shape in the near-peak model: how much brighter a photon walk on the mesh is than the
flat half-space's profile at the same material, cell by cell (a step of :mod:`.near_peak`).

The half-space's profile :math:`\sigma_t^2 f(\sigma_t r; \alpha)` (:mod:`translucency.model.half_space`)
assumes a flat surface.  On a convex part the surface falls away from its tangent plane by about
:math:`r^2 / 2\rho` (ρ the radius of curvature), into the light diffusing beneath: on a 15 mm ball in
skin1 the exits at 2–3 mm from the hit are 14–25 % brighter than the half-space's, at 4–6 mm 28–45 %.  A
ring fitted with the flat profile reads that excess as a shallower profile, and the peak comes out low
(0.5–0.7 of the tally's on two of three shots, docs/object-rig.md §4).

The gain of a cell v is the ratio of a photon walk on the mesh itself
(:func:`translucency.acquire.mesh_walk.mesh_random_walk`, index-matched, entering at the hit along the
inward normal, a homogeneous medium of the fitted σ_t and α) to the half-space's cell means, summed over
the cells within :math:`h_v = \max(\bar e, \beta\, r_v)` of v (ē the mean edge, r_v the distance from the
hit, β = :data:`NEIGHBOURHOOD`) so that a cell far from the hit still holds enough exits:

.. math::  G_v = \frac{\sum_{|x_u - x_v| \le h_v} A_u R^{walk}_u}{\sum_{|x_u - x_v| \le h_v} A_u H_u},
   \qquad H_u = \frac{1}{A_u}\int \phi_u\, \sigma_t^2 f(\sigma_t |y - x_i|; \alpha)\, dA(y).

The near-peak model is then :math:`G_v \cdot \sigma_t^2 f(\sigma_t r; \alpha)` on cell v, refitted; the
walk's material follows the fit (:data:`.near_peak.SHAPE_ITERATIONS` times).  A profile steeper than the
half-space's at the same material (a horn's tip, a thin part) shows as a gain above 1 too.

Units: mm, R_d in mm⁻² per unit incident power.
"""

from __future__ import annotations

import numpy as np

from ...acquire.mesh_walk import EXIT, mesh_random_walk
from ...acquire.volume import Volume
from ...model.half_space import half_space_R_d
from .near_peak import cell_quadrature

#: photons a channel of each walk
PHOTONS = 200_000
#: the neighbourhood a gain is summed over, as a share of the cell's distance from the hit
NEIGHBOURHOOD = 0.3
#: a gain is kept within these bounds (a cell with no exit nearby is not made dark by the walk's noise)
GAIN_RANGE = (0.25, 4.0)


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

    Examples
    --------
    On a ball of 15 mm the walk is brighter than the flat profile away from the hit, and equal at it:

    >>> import trimesh
    >>> from translucency.mitsuba import mesh_scene
    >>> mesh = trimesh.creation.icosphere(4, radius=15.0)
    >>> shape = MeshWalkGain(mesh, mesh_scene(mesh), mesh.vertices[0], mesh.vertex_normals[0])
    >>> G = shape.gain([(1.0, 0.9)] * 3, reach=4.0)  # doctest: +SKIP
    >>> r = np.linalg.norm(mesh.vertices - mesh.vertices[0], axis=1)  # doctest: +SKIP
    >>> bool(abs(G[0, 0] - 1) < 0.05), bool(np.median(G[(r > 2) & (r < 4), 0]) > 1.05)  # doctest: +SKIP
    (True, True)
    """

    def __init__(self, mesh, scene, hit, normal, *, seed: int = 0, photons: int = PHOTONS):
        self.mesh, self.scene = mesh, scene
        self.hit = np.asarray(hit, dtype=np.float64)
        self.normal = np.asarray(normal, dtype=np.float64) / np.linalg.norm(normal)
        self.seed, self.photons = seed, photons

    def gain(self, params, reach: float) -> np.ndarray:
        """(V, 3) gains: per channel, the walk at ``params[ch]`` = (σ_t mm⁻¹, α) against the half-space at
        the same; 1 beyond ``reach`` mm of the hit and in a channel whose params are None."""
        from scipy.spatial import cKDTree  # heavy: SciPy's spatial index loads where a peak is recovered

        from ...acquire.mesh import splat_exits  # the tally's own rule: an exit shared among its corners

        mesh = self.mesh
        verts = np.asarray(mesh.vertices, dtype=np.float64)
        V = len(verts)
        r = np.linalg.norm(verts - self.hit, axis=1)
        edge = float(np.mean(mesh.edges_unique_length))
        near = np.flatnonzero(r <= reach)
        h = np.maximum(edge, NEIGHBOURHOOD * r[near])  # each gain's neighbourhood radius, mm
        # the cells any neighbourhood reaches: their half-space cell means are needed too
        zone = np.flatnonzero(r <= reach + NEIGHBOURHOOD * reach + edge)
        pts, w, owner = cell_quadrature(mesh, zone, toward=self.hit)
        dist = np.linalg.norm(pts - self.hit, axis=1)
        tree = cKDTree(verts[zone])
        neighbours = tree.query_ball_point(verts[near], h)
        G = np.ones((V, 3))
        for ch, p in enumerate(params):
            if p is None:
                continue
            sigma_t, albedo = (float(v) for v in p)
            volume = Volume.homogeneous(
                (1, 1, 1), float(np.max(mesh.extents)) + 1.0, [albedo * sigma_t] * 3,
                [(1 - albedo) * sigma_t] * 3, eta=1.0,
            )  # fmt: skip
            walk = mesh_random_walk(
                self.scene, mesh.bounds, volume, ch, self.hit[None], self.normal[None], self.photons,
                seed=self.seed + 7919 * ch, index_matched=True,
            )  # fmt: skip
            out = walk.code == EXIT
            point = np.zeros(int(out.sum()), dtype=np.int64)  # one entry point
            counts = splat_exits(mesh, point, walk.face[out], walk.position[out], 1)[0]
            walked = counts[zone] / self.photons  # A_u R^walk_u per cell (the share of the photons)
            H = half_space_R_d(dist, sigma_t, albedo)
            flat = np.bincount(owner, w * H, minlength=len(zone))  # A_u H_u: the half-space per cell
            ratio = [walked[n].sum() / max(flat[n].sum(), 1e-300) for n in neighbours]
            G[near, ch] = np.clip(ratio, *GAIN_RANGE)
        return G


__all__ = ["MeshWalkGain", "PHOTONS"]
