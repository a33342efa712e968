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
incidence), or along a given direction in the air, reflected with Fresnel's share at
its angle and refracted in (oblique incidence); a photon that leaves is tallied at
its exit point with its direction of flight.  A ray that
misses the mesh from inside means the photon escaped through a crack: it is
reported as ``KILLED`` (none in a watertight mesh; the tests count them).

**Re-entry** (``reentry=True``): on a non-convex scan light that leaves one part may fly through the air
into another — a horn's tip 0.7 mm thick beside the head, a leg beside a leg.  A photograph sees it
where it finally escapes, so the photon, refracted out, is followed through the air (state
``OUTSIDE``, its last exit point kept): a ray that misses the mesh escapes and is tallied at that exit;
one that hits it is reflected (Fresnel, staying outside) or refracted back in and walks on.  On a
convex mesh nothing changes, bit for bit (no ray from its surface outwards meets it again, and no random
number is drawn for a photon that escapes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mitsuba import drjit, mitsuba
from .transport import ABSORBED, ACTIVE, KILLED, _medium_event, _walk_setup
from .volume import Volume

EXIT = 1  # left through the surface
OUTSIDE = 5  # in flight through the air between two parts of the mesh (re-entry); not a final state


@dataclass
class MeshWalkResult:
    """Where each photon ended (NumPy arrays, one entry per photon)."""

    code: np.ndarray  # EXIT, ABSORBED, KILLED, or -1 for specular reflection at entry
    position: np.ndarray  # (n, 3) exit point for EXIT, mm
    face: np.ndarray  # (n,) triangle the photon left through (EXIT only)
    direction: np.ndarray  # (n, 3) flight direction at the end (EXIT: the exit direction, outwards)
    steps: int
    scatters: np.ndarray | None = None  # (n,) real scattering events of each photon (albedo reweighting)
    length: np.ndarray | None = None  # (n,) path length inside the medium, mm (σ_t reweighting)


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
    reentry: bool = False,
    max_steps: int = 200_000,
    incoming: np.ndarray | None = None,
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
    reentry : bool
        Follow light that leaves through the air into another part of the mesh (module docstring);
        ``False``: every photon that leaves is tallied where it first left.
    incoming : ndarray, shape (P, 3), optional
        Each beam's direction of flight in the air as it reaches the surface (unit, against the outward
        normal), for beams that arrive obliquely: reflected with Fresnel's share at its angle and refracted
        in by Snell's law (straight on where index-matched).  Default: along −``normal`` (normal
        incidence).

    Returns
    -------
    MeshWalkResult
    """
    mi, dr = mitsuba(), drjit()
    UInt32 = mi.UInt32
    total = len(entry) * n_photons
    lo, hi = ([float(v) for v in b] for b in np.asarray(bounds, dtype=np.float64))  # Python floats: no NumPy
    eta = 1.0 if index_matched else volume.eta
    eps = 1e-4 * max(h - l for h, l in zip(hi, lo))  # ray offset off the surface, mm

    sigma_s, sigma_t, majorant, point, rng = _walk_setup(
        mi, dr, volume, channel, total, n_photons, seed, first_point
    )
    n_in = _gathered(mi, dr, normal, point)
    pos = _gathered(mi, dr, entry, point) - n_in * eps
    omega = None if incoming is None else _gathered(mi, dr, np.asarray(incoming, dtype=np.float64), point)
    specular, direction = _enter(mi, dr, rng, n_in, eta, omega)
    code = dr.select(specular, UInt32(EXIT + 100), UInt32(ACTIVE))
    steps, face, scatters = UInt32(0), UInt32(0), UInt32(0)
    length = mi.Float(0.0)  # the path inside the medium, mm
    exit_pos = mi.Vector3f(pos)  # the last exit point of a photon in the air (re-entry)

    pos, direction, rng, code, steps, face, scatters, length, exit_pos = dr.while_loop(
        state=(pos, direction, rng, code, steps, face, scatters, length, exit_pos),
        cond=_in_flight,
        body=_walk_body(
            mi, dr, scene, volume, (sigma_s, sigma_t, majorant), (lo, hi), eta, eps, reentry, max_steps
        ),
        label="mesh_photon_walk",
    )
    return _mesh_result(dr, pos, direction, code, steps, face, scatters, length)


def _walk_body(
    mi, dr, scene, volume: Volume, medium, box, eta: float, eps: float, reentry: bool, max_steps: int
):
    """The loop's body: one step of every photon (a flight to a collision or to the surface, and re-entry)."""
    majorant = medium[2]  # (σ_s, σ_t, their majorant), mm⁻¹
    UInt32 = mi.UInt32

    def body(pos, direction, rng, code, steps, face, scatters, length, exit_pos):
        active = code == ACTIVE
        outside = code == OUTSIDE
        # tentative free flight against the majorant, and the distance to the surface (inside, or
        # through the air for a photon between two parts)
        t = -dr.log(1.0 - rng.next_float32()) / majorant
        si = scene.ray_intersect(mi.Ray3f(pos, direction), active | outside)
        # a ray that misses (si.t = inf) still collides in the medium: a ray through a vertex or along an
        # edge can slip between triangles (the first flight from an icosphere's pole is one); only a photon
        # that would fly on without a surface ahead has escaped through a crack
        collide = active & (t < si.t)
        escaped = active & ~si.is_valid() & ~collide

        # -- inside: real or null collision (voxel of the object-space volume) ---------------
        p_c, scatter, absorb, new_dir = _collision(
            mi, dr, volume, medium, box, pos, direction, t, collide, rng
        )

        # -- surface: Fresnel reflection (TIR included) or exit -------------------------------
        hit, n, reflect, leave, refl_dir = _at_surface(mi, dr, rng, si, direction, active, collide, eta)
        # the flight inside: to the collision, or to the surface
        length = length + dr.select(collide, t, dr.select(hit, si.t, 0.0))

        pos = dr.select(collide, p_c, dr.select(hit, si.p - n * eps, pos))
        face = dr.select(leave, si.prim_index, face)
        direction = dr.select(scatter, new_dir, dr.select(reflect, refl_dir, direction))
        code = dr.select(absorb, UInt32(ABSORBED), code)
        if reentry:
            pos, direction, code, exit_pos = _through_air(
                mi, dr, rng, si, n, leave, outside, pos, direction, code, exit_pos, eta, eps
            )
        else:
            pos = dr.select(leave, si.p, pos)
            code = dr.select(leave, UInt32(EXIT), code)
        code = dr.select(escaped, UInt32(KILLED), code)
        steps = steps + dr.select(active | outside, 1, 0)
        scatters = scatters + dr.select(scatter, 1, 0)
        running = (code == ACTIVE) | (code == OUTSIDE)
        code = dr.select(running & (steps >= max_steps), UInt32(KILLED), code)
        return pos, direction, rng, code, steps, face, scatters, length, exit_pos

    return body


def _collision(mi, dr, volume: Volume, medium, box, pos, direction, t, collide, rng):
    """A real or null collision at pos + t d (mm), in its voxel of the volume over ``box`` (lo, hi, mm):
    the point, the scatter and absorb masks and the scattered direction."""
    sigma_s, sigma_t, majorant = medium
    lo, hi = box
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
    return p_c, scatter, absorb, new_dir


def _in_flight(pos, direction, rng, code, steps, face, scatters, length, exit_pos):
    """The loop's condition: the photons inside the medium or in flight through the air."""
    return (code == ACTIVE) | (code == OUTSIDE)


def _gathered(mi, dr, a: np.ndarray, point):
    """Each photon's row of the per-point array ``a`` (P, 3), as a float32 3-vector."""
    Float = mi.Float
    return mi.Vector3f(*(dr.gather(Float, Float(a[:, k].astype(np.float32)), point) for k in range(3)))


def _enter(mi, dr, rng, n_in, eta: float, omega):
    """At entry: which photons Fresnel reflects (one draw each) and the direction of the others in."""
    if omega is None:  # -- entry: Fresnel at normal incidence, then straight in along −n ------
        F_in = float(mi.fresnel(mi.Float(1.0), mi.Float(eta))[0][0]) if eta != 1.0 else 0.0
        specular = rng.next_float32() < F_in
        direction = -n_in
    else:  # -- oblique entry: Fresnel at cos θ_i = −ω·n, refracted in (Snell, 1 → η) -----------
        cos_in = dr.maximum(-dr.dot(omega, n_in), 1e-6)
        specular = rng.next_float32() < _fresnel(mi, cos_in, eta)
        direction = _refract(dr, omega, -n_in, 1.0 / eta)
    return specular, direction


def _at_surface(mi, dr, rng, si, direction, active, collide, eta: float):
    """At the surface ahead: who reaches it, the normal along the flight, Fresnel's reflection (one draw)
    or exit, and the mirror direction."""
    hit = active & si.is_valid() & ~collide
    n = dr.normalize(si.n)
    n = dr.select(dr.dot(n, direction) < 0, -n, n)  # the normal on the far side, along the flight
    cos_i = dr.abs(dr.dot(direction, n))
    F = _fresnel(mi, -cos_i, eta)
    reflect = hit & (rng.next_float32() < F)
    leave = hit & ~reflect
    refl_dir = _reflect(dr, direction, n)
    return hit, n, reflect, leave, refl_dir


def _through_air(mi, dr, rng, si, n, leave, outside, pos, direction, code, exit_pos, eta: float, eps: float):
    """Re-entry: the leaving photons refracted out (exit point kept); those in the air escape (tallied at
    that exit), bounce off the surface or are refracted back in."""
    UInt32 = mi.UInt32
    # -- leaving: refracted out into the air, the exit point kept for the tally ----------
    exit_pos = dr.select(leave, si.p, exit_pos)
    pos = dr.select(leave, si.p + n * eps, pos)
    direction = dr.select(leave, _refract(dr, direction, n, eta), direction)
    code = dr.select(leave, UInt32(OUTSIDE), code)

    # -- in the air: escaped (tallied at the last exit), or back at the surface ----------
    escape = outside & ~si.is_valid()
    land = outside & si.is_valid()
    m = dr.normalize(si.n)
    m = dr.select(dr.dot(m, direction) > 0, -m, m)  # the outward normal, against the flight
    cos_o = dr.abs(dr.dot(direction, m))
    F_o = _fresnel(mi, cos_o, eta)
    # (the draw advances only the landing lanes: on a convex mesh the walk is the same bit for bit)
    bounce = land & (rng.next_float32(land) < F_o)  # reflected off the outside: stays in the air
    enter = land & ~bounce
    pos = dr.select(bounce, si.p + m * eps, dr.select(enter, si.p - m * eps, pos))
    direction = dr.select(
        bounce,
        _reflect(dr, direction, m),
        dr.select(enter, _refract(dr, direction, -m, 1.0 / eta), direction),
    )
    pos = dr.select(escape, exit_pos, pos)
    code = dr.select(escape, UInt32(EXIT), dr.select(enter, UInt32(ACTIVE), code))
    return pos, direction, code, exit_pos


def _mesh_result(dr, pos, direction, code, steps, face, scatters, length) -> MeshWalkResult:
    """The walk's end as NumPy: codes (specular −1), exit points and directions, faces, steps, scatters."""
    dr.eval(pos, code, steps, face, scatters, length)
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
        length=np.asarray(length).astype(np.float64),
    )


def _fresnel(mi, cos_theta_i, eta: float):
    """Mitsuba's unpolarised Fresnel reflectance at a boundary of relative index ``eta`` (interior over
    exterior; ``cos_theta_i`` < 0 from inside), zero where index-matched."""
    return mi.fresnel(cos_theta_i, mi.Float(eta))[0] if eta != 1.0 else mi.Float(0.0)


def _reflect(dr, d, n):
    """The mirror direction of ``d`` about the unit normal ``n`` (either side): d − 2 (d · n) n."""
    return d - 2.0 * dr.dot(d, n) * n


def _refract(dr, d, n, eta: float):
    r"""The direction refracted through a boundary with unit normal ``n`` along the flight
    (``dot(d, n) > 0``), ``eta`` the index before over the index after (Snell's law):

    .. math:: d_t = \eta d + (\cos\theta_t - \eta \cos\theta_i)\, n

    (total internal reflection is the Fresnel step's, so :math:`\cos\theta_t` is real)."""
    if eta == 1.0:
        return d
    cos_i = dr.dot(d, n)
    cos_t = dr.sqrt(dr.maximum(1.0 - eta * eta * (1.0 - cos_i * cos_i), 0.0))
    return dr.normalize(eta * d + (cos_t - eta * cos_i) * n)
