"""Laser hits: where each shot enters the mesh (mm) and the vertex it is snapped to, the incident x_i.

A shot's ``hit`` in ``object.json`` (:mod:`.setup`) is a vertex index, a point (moved to the closest
point of the surface, refused beyond :data:`HIT_TOLERANCE_EDGES` mean edge lengths) or the laser's ray
(cast against the mesh by Mitsuba; a miss or a back-facing first hit is refused).
"""

from __future__ import annotations

import numpy as np

from ..._validate import TranslucencyError, plain
from ...mitsuba import rays
from .setup import ObjectRig

#: the farthest a laser hit given as a point may lie from the surface, in mean edge lengths
HIT_TOLERANCE_EDGES = 0.5


def incident_vertices(rig: ObjectRig, mesh, scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each shot's nearest vertex (P,), its hit as a point on the surface (P, 3) and the unit direction
    toward the laser (P, 3): the ray's, reversed, or the vertex normal where the hit is given as a vertex or
    a point (the rig then says nothing of the beam's direction: taken along the normal).  A hit off the
    mesh, on a back-facing side or out of range is refused in one line naming the shot."""
    from scipy.spatial import cKDTree  # heavy: SciPy's spatial index loads where hits are snapped

    verts = np.asarray(mesh.vertices, dtype=np.float64)
    edge = float(np.mean(mesh.edges_unique_length))
    tree = cKDTree(verts)
    points = np.zeros((len(rig.shots), 3))
    toward = np.full((len(rig.shots), 3), np.nan)
    for shot in rig.shots:
        where = f"{rig.path}: shot {shot.index}: hit"
        h = shot.hit
        if "vertex" in h:
            v = h["vertex"]
            if not isinstance(v, int) or not 0 <= v < len(verts):
                raise TranslucencyError(f"{where}: vertex {v!r} is not a vertex index (0..{len(verts) - 1})")
            points[shot.index] = verts[v]
        elif "point" in h:
            p = np.asarray(h["point"], dtype=np.float64).ravel()
            if p.shape != (3,) or not np.isfinite(p).all():
                raise TranslucencyError(f"{where}: point must be three finite numbers (mm)")
            closest, dist = _closest_on_surface(mesh, tree, p)
            if dist > HIT_TOLERANCE_EDGES * edge:
                raise TranslucencyError(
                    f"{where}: point {plain(p)} lies {dist:.3g} mm off the mesh "
                    f"(> {HIT_TOLERANCE_EDGES} edge)"
                )
            points[shot.index] = closest
        else:
            ray = h["ray"] if isinstance(h["ray"], dict) else {}
            o = np.asarray(ray.get("origin", ()), dtype=np.float64).ravel()
            d = np.asarray(ray.get("direction", ()), dtype=np.float64).ravel()
            if o.shape != (3,) or d.shape != (3,) or not (np.isfinite(o).all() and np.isfinite(d).all()):
                raise TranslucencyError(f"{where}: ray needs origin and direction, three numbers each")
            if np.linalg.norm(d) == 0:
                raise TranslucencyError(f"{where}: ray direction is zero")
            d = d / np.linalg.norm(d)
            si = scene.ray_intersect(rays(o[None], d[None]))
            if not bool(np.asarray(si.is_valid())[0]):
                raise TranslucencyError(f"{where}: the laser ray misses the mesh")
            face = int(np.asarray(si.prim_index)[0])
            if np.dot(mesh.face_normals[face], d) >= 0:
                raise TranslucencyError(f"{where}: the laser ray hits a back-facing side of the mesh first")
            points[shot.index] = o + float(np.asarray(si.t)[0]) * d
            toward[shot.index] = -d
    _, incident = tree.query(points)
    incident = np.asarray(incident, dtype=np.int64)
    normals = np.asarray(mesh.vertex_normals, dtype=np.float64)[incident]
    return incident, points, np.where(np.isnan(toward), normals, toward)


def _closest_on_surface(mesh, tree, p: np.ndarray) -> tuple[np.ndarray, float]:
    """The surface point nearest ``p`` among the triangles around its 16 nearest vertices; its distance."""
    import trimesh  # heavy: trimesh loads where hits are snapped

    _, near = tree.query(p, k=min(16, len(mesh.vertices)))
    faces = np.unique(
        np.concatenate([mesh.vertex_faces[v][mesh.vertex_faces[v] >= 0] for v in np.atleast_1d(near)])
    )
    tri = np.asarray(mesh.triangles)[faces]
    q = trimesh.triangles.closest_point(tri, np.repeat(p[None], len(tri), axis=0))
    d = np.linalg.norm(q - p, axis=1)
    return q[np.argmin(d)], float(d.min())
