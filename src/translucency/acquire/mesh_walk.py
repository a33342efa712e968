r"""Photon random walks inside a closed mesh, its boundary traced by Mitsuba 3.

The estimator is the one of :mod:`translucency.acquire.transport` — delta
tracking through a voxel volume, Henyey–Greenstein scattering, Fresnel
reflection (with total internal reflection) at a smooth dielectric boundary —
with the box replaced by an arbitrary watertight triangle mesh: the distance
to the boundary along the flight direction is ``scene.ray_intersect`` and the
Fresnel term uses the hit's geometric normal.

The volume lives in object space over the mesh's bounding box: voxel
``[iz, iy, ix]`` covers ``x in lo.x + [ix, ix+1) vox``, ``y in lo.y + [iy, iy+1) vox``
and ``z in hi.z - (iz+1, iz] vox`` (z index 0 at the top, as for slabs).

Each pencil beam enters at a surface point along the inward normal (normal
incidence); a photon that leaves is tallied at its exit point.  A ray that
misses the mesh from inside means the photon escaped through a crack: it is
reported as ``KILLED`` (none in a watertight mesh; the tests count them).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mitsuba import drjit, mitsuba
from .transport import ABSORBED, ACTIVE, KILLED, _medium_event, _walk_setup
from .volume import Volume

EXIT = 1  # left through the surface


@dataclass
class MeshWalkResult:
    """Where each photon ended (NumPy arrays, one entry per photon)."""

    code: np.ndarray  # EXIT, ABSORBED, KILLED, or -1 for specular reflection at entry
    position: np.ndarray  # (n, 3) exit point for EXIT, mm
    face: np.ndarray  # (n,) triangle the photon left through (EXIT only)
    direction: np.ndarray  # (n, 3) flight direction at the end (EXIT: the exit direction, outwards)
    steps: int
    scatters: np.ndarray | None = None  # (n,) real scattering events of each photon (albedo reweighting)


def mesh_random_walk(
    scene,
    bounds: np.ndarray,
    volume: Volume,
    channel: int,
    entry: np.ndarray,
    normal: np.ndarray,
    n_photons: int,
    *,
    seed: int = 0,
    first_point: int = 0,
    index_matched: bool = False,
    max_steps: int = 200_000,
) -> MeshWalkResult:
    """Trace ``n_photons`` photons from each entry point into the mesh, in one wavefront.

    Parameters
    ----------
    scene : mitsuba.Scene
        From :func:`mesh_scene`.
    bounds : ndarray, shape (2, 3)
        The mesh's bounding box (lo, hi), mm: where the volume sits.
    volume : Volume
        Coefficients over the bounding box (its size must cover it).
    channel : int
        Colour channel.
    entry, normal : ndarray, shape (P, 3)
        Entry points on the surface and their outward unit normals.
    n_photons : int
        Photons per entry point.

    Returns
    -------
    MeshWalkResult
    """
    mi, dr = mitsuba(), drjit()

    Float, UInt32 = mi.Float, mi.UInt32
    total = len(entry) * n_photons
    lo, hi = ([float(v) for v in b] for b in np.asarray(bounds, dtype=np.float64))  # Python floats: no NumPy
    eta = 1.0 if index_matched else volume.eta
    eps = 1e-4 * max(h - l for h, l in zip(hi, lo))  # ray offset off the surface, mm

    sigma_s, sigma_t, majorant, point, rng = _walk_setup(
        mi, dr, volume, channel, total, n_photons, seed, first_point
    )

    # -- entry: Fresnel at normal incidence, then straight in along −n --------------------
    F_in = float(mi.fresnel(Float(1.0), Float(eta))[0][0]) if eta != 1.0 else 0.0
    specular = rng.next_float32() < F_in

    def gathered(a):
        return mi.Vector3f(*(dr.gather(Float, Float(a[:, k].astype(np.float32)), point) for k in range(3)))

    n_in = gathered(normal)
    pos = gathered(entry) - n_in * eps
    direction = -n_in
    code = dr.select(specular, UInt32(EXIT + 100), UInt32(ACTIVE))
    steps = UInt32(0)
    face = UInt32(0)
    scatters = UInt32(0)

    def cond(pos, direction, rng, code, steps, face, scatters):
        return code == ACTIVE

    def body(pos, direction, rng, code, steps, face, scatters):
        active = code == ACTIVE
        # tentative free flight against the majorant, and the distance to the surface
        t = -dr.log(1.0 - rng.next_float32()) / majorant
        si = scene.ray_intersect(mi.Ray3f(pos, direction), active)
        # a ray that misses (si.t = inf) still collides in the medium: a ray through a vertex or along an
        # edge can slip between triangles (the first flight from an icosphere's pole is one); only a photon
        # that would fly on without a surface ahead has escaped through a crack
        collide = active & (t < si.t)
        escaped = active & ~si.is_valid() & ~collide

        # -- inside: real or null collision (voxel of the object-space volume) ---------------
        p_c = pos + direction * t
        scatter, absorb, new_dir = _medium_event(
            mi,
            dr,
            volume,
            sigma_s,
            sigma_t,
            majorant,
            p_c.x - lo[0],
            p_c.y - lo[1],
            hi[2] - p_c.z,
            collide,
            rng,
            direction,
        )

        # -- surface: Fresnel reflection (TIR included) or exit -------------------------------
        hit = active & si.is_valid() & ~collide
        n = dr.normalize(si.n)
        n = dr.select(dr.dot(n, direction) < 0, -n, n)  # the normal on the far side, along the flight
        cos_i = dr.abs(dr.dot(direction, n))
        F = mi.fresnel(-cos_i, Float(eta))[0] if eta != 1.0 else Float(0.0)
        reflect = hit & (rng.next_float32() < F)
        leave = hit & ~reflect
        refl_dir = direction - 2.0 * dr.dot(direction, n) * n

        pos = dr.select(collide, p_c, dr.select(hit, si.p - n * eps, pos))
        pos = dr.select(leave, si.p, pos)
        face = dr.select(leave, si.prim_index, face)
        direction = dr.select(scatter, new_dir, dr.select(reflect, refl_dir, direction))
        code = dr.select(absorb, UInt32(ABSORBED), code)
        code = dr.select(leave, UInt32(EXIT), code)
        code = dr.select(escaped, UInt32(KILLED), code)
        steps = steps + dr.select(active, 1, 0)
        scatters = scatters + dr.select(scatter, 1, 0)
        code = dr.select((code == ACTIVE) & (steps >= max_steps), UInt32(KILLED), code)
        return pos, direction, rng, code, steps, face, scatters

    pos, direction, rng, code, steps, face, scatters = dr.while_loop(
        state=(pos, direction, rng, code, steps, face, scatters),
        cond=cond,
        body=body,
        label="mesh_photon_walk",
    )
    dr.eval(pos, code, steps, face, scatters)
    code_np = np.asarray(code).astype(np.int64)
    code_np[code_np == EXIT + 100] = -1
    position = np.stack([np.asarray(pos.x), np.asarray(pos.y), np.asarray(pos.z)], axis=1)
    flight = np.stack([np.asarray(direction.x), np.asarray(direction.y), np.asarray(direction.z)], axis=1)
    return MeshWalkResult(
        code=code_np,
        position=position,
        face=np.asarray(face).astype(np.int64),
        direction=flight,
        steps=int(dr.sum(steps)[0]),
        scatters=np.asarray(scatters).astype(np.int64),
    )
