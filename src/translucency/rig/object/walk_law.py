r"""The exit law of the transport itself, per cell and camera: photon walks on the scan at the material the
near peak fitted (``exit_law: "walk"``, a step of :mod:`.importer`).

A camera sees a cell's exitance M through one direction; what it reads is the radiance there,
:math:`\pi L = \gamma M`, and near the hit γ depends on the view and on where the cell lies (light leaves
leaning away from the hit and following the surface's shape: :mod:`.exit_law`).  A law pooled over every
vertex of a band of distance is not the law of the vertices a camera sees (docs/validation/object-rig.md,
Limits).  This
one is the transport's own, cell by cell and camera by camera: for each shot, a walk on the mesh
(:func:`translucency.acquire.mesh_walk.mesh_random_walk`, a homogeneous medium at the (σ_t, α) per
channel the near peak fitted to the same shot under π L, entering at the hit, through the boundary of
the rig) gives each exit e its position, its cell weights :math:`\phi_v(e)` and its direction
:math:`\omega_e`, and

.. math:: \gamma_{v c} = \frac{\sum_{e} \phi_v(e)\, [\omega_e\cdot\hat c_e > \cos\theta_c]
                              / (\mu_{e c}\, \Omega'_c)}{\sum_e \phi_v(e) / \pi},
          \qquad \Omega'_c = \pi (1 - \cos^2\theta_c),

with :math:`\hat c_e` the direction from the exit to camera c's centre, :math:`\mu_{ec}` its cosine to
the exit's face normal and θ_c = :data:`CONE_DEG`: an exit flux n_cap in the cap over an area A is a
radiance :math:`L = n_{cap}/(A\,\mu\,\Omega'_c)` (exact for a constant L over the cap), the exitance
n/A is Lambertian radiance n/(πA).  Both sums run over the cells within :math:`h_v = \min(\max(\bar e_v/2,\,
0.3\,r_v),\, 2\ \mathrm{mm})` of v on the same side (as the shape's gains are pooled,
:mod:`.shape_gain`); where fewer than :data:`MIN_EXITS` exits fall there γ is 1.  A pixel takes the mean
of its cells' γ weighted as its footprint covers them.  The import then converts twice: π L for the near
peak's first fit, and πL/γ with the walk's law at that fit's material.

Units: mm, degrees.
"""

from __future__ import annotations

import numpy as np

from ...acquire.mesh import exit_barycentric
from ...acquire.mesh_walk import EXIT
from .shape_gain import homogeneous_walk, mean_edge, same_side_pairs

#: the half-angle (degrees) of the cap about a camera's direction within which an exit counts for it
CONE_DEG = 20.0
#: photons of each channel's walk
PHOTONS = 100_000
#: a cell's law is 1 where its neighbourhood holds fewer exits
MIN_EXITS = 40
#: the least view cosine an exit's radiance is divided by (a cap at grazing views)
MU_MIN = 0.1
#: the widest neighbourhood (mm) a cell's law is pooled over
MAX_NEIGHBOURHOOD_MM = 2.0


class ShotWalkLaw:
    """γ per cell and camera (V, 3) of one shot, from a walk at ``params`` = [(σ_t mm⁻¹, α)] × 3.

    Examples
    --------
    >>> import numpy as np
    >>> import trimesh
    >>> from translucency.mitsuba import mesh_scene
    >>> from translucency.rig.object.walk_law import ShotWalkLaw
    >>> ball = trimesh.creation.icosphere(3, radius=6.0)
    >>> law = ShotWalkLaw(ball, mesh_scene(ball), ball.vertices[0], ball.vertex_normals[0],
    ...                   [(1.0, 0.95)] * 3, [np.array([0.0, 0.0, 60.0])], photons=4_000)
    >>> law.gamma[0].shape
    (642, 3)
    """

    def __init__(self, mesh, scene, hit, normal, params, centres, *, eta=1.0, seed=0, photons=PHOTONS):
        V = np.asarray(mesh.vertices, dtype=np.float64)
        hit, normal = np.asarray(hit, np.float64), np.asarray(normal, np.float64)
        r = np.linalg.norm(V - hit, axis=1)
        h = np.minimum(np.maximum(0.5 * mean_edge(mesh), 0.3 * r), MAX_NEIGHBOURHOOD_MM)
        every = np.arange(len(V))
        rows, cols = same_side_pairs(mesh, every, every, h)
        cos_c = np.cos(np.radians(CONE_DEG))
        omega_c = np.pi * (1.0 - cos_c**2)
        self.gamma = [np.ones((len(V), 3)) for _ in centres]
        for ch, (sigma_t, albedo) in enumerate(params):
            if sigma_t is None:
                continue
            walk = homogeneous_walk(
                mesh, scene, hit, normal, sigma_t, albedo, photons, seed=seed + 7919 * ch, eta=eta
            )
            out = np.flatnonzero(walk.code == EXIT)
            pos = np.asarray(walk.position[out], dtype=np.float64)
            w = np.asarray(walk.direction[out], dtype=np.float64)
            w /= np.linalg.norm(w, axis=1, keepdims=True)
            tri, bary = exit_barycentric(mesh, walk.face[out], pos)

            def per_cell(weight, tri=tri, bary=bary):  # Σ_e φ_v(e) weight_e over each cell's neighbourhood
                own = np.bincount(tri.ravel(), (bary * weight[:, None]).ravel(), minlength=len(V))
                return np.bincount(rows, own[cols], minlength=len(V))

            exits = per_cell(np.ones(len(out)))
            known = exits >= MIN_EXITS
            face_normal = np.asarray(mesh.face_normals, dtype=np.float64)[walk.face[out]]
            for c, centre in enumerate(centres):
                to_cam = centre - pos
                to_cam /= np.linalg.norm(to_cam, axis=1, keepdims=True)
                toward = np.einsum("ij,ij->i", w, to_cam) > cos_c
                mu = np.einsum("ij,ij->i", face_normal, to_cam)  # the view's cosine at the exit
                seen = per_cell(np.where(toward, 1.0 / np.maximum(mu, MU_MIN), 0.0))
                self.gamma[c][known, ch] = (seen[known] / omega_c) / (exits[known] / np.pi)

    def pixel_gamma(self, c: int, surface_map) -> np.ndarray:
        """γ (n, 3) at camera ``c``'s used pixels: its cells' γ, weighted as each pixel's footprint covers
        them."""
        W = surface_map.W[:, surface_map.used]  # (V, n)
        cover = np.asarray(W.sum(axis=0)).ravel()
        return (W.T @ self.gamma[c]) / np.maximum(cover, 1e-30)[:, None]


__all__ = ["ShotWalkLaw", "CONE_DEG", "PHOTONS", "MIN_EXITS"]
