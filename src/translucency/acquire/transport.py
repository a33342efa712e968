r"""Photon random walks through a heterogeneous slab, as Dr.Jit wavefront loops.

One photon per lane.  Each walk is the analog Monte Carlo estimator of the
radiative transfer equation in the slab of :mod:`translucency.acquire.volume`:

* **entry**: a pencil beam hits the top face at :math:`\vec x_i` at angle
  :math:`\theta_{inc}`; with probability :math:`F(\cos\theta_{inc}, \eta)`
  (Mitsuba's exact unpolarised Fresnel term) the photon is reflected
  specularly and tallied apart, otherwise it refracts into the slab;
* **free flight**: delta (Woodcock) tracking against the per-channel majorant
  :math:`\bar\sigma = \max \sigma_t`: a tentative distance
  :math:`t = -\ln(1-\xi)/\bar\sigma`; at the tentative point the photon
  scatters with probability :math:`\sigma_s/\bar\sigma`, is absorbed with
  :math:`\sigma_a/\bar\sigma`, and flies on (null collision) otherwise — which
  samples the heterogeneous medium without bias;
* **scattering**: a new direction from the Henyey–Greenstein phase function;
* **boundary**: at any face of the box, Fresnel reflection (total internal
  reflection beyond the critical angle) with probability F, else the photon
  leaves; an index-matched slab (:math:`\eta = 1`) has no reflection.

A photon leaving through the top face is tallied at its exit position.  With
N photons per incident point, the count :math:`n_{px}` in a pixel of area
:math:`p^2` estimates :math:`R_d(\vec x_i, \vec x_o) = n_{px}/(N p^2)` in mm⁻²
per unit incident power, with binomial variance
:math:`\hat R_d (1/(p^2) - \hat R_d)/N`.  Photons are numbered globally
(point index × N + photon), and each draws from its own PCG32 stream seeded
by that number, so the streams never repeat across batches.  They are not
independent of the batching bit for bit: Dr.Jit's ``PCG32(size, initstate,
initseq)`` also adds the lane index, so the same photon traced in another
batch layout draws another (equally valid) stream.  Planar acquisitions use
fixed chunks, so a resumed run is identical to an uninterrupted one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError
from ..mitsuba import drjit, mitsuba
from .volume import Volume

# exit codes of a photon
ACTIVE, TOP, OTHER_FACE, ABSORBED, KILLED = 0, 1, 2, 3, 4


@dataclass
class WalkResult:
    """Where each photon of one batch ended (NumPy arrays, one entry per photon)."""

    code: np.ndarray  # exit code: TOP, OTHER_FACE, ABSORBED, KILLED, or -1 for specular at entry
    x: np.ndarray  # exit position (mm) for TOP exits
    y: np.ndarray
    steps: int  # loop iterations summed over photons (free-flight events incl. null collisions)
    cos_exit: np.ndarray | None = (
        None  # cosine of the exit direction to the top normal (+z) for TOP exits, else 0
    )
    exit_xy: np.ndarray | None = None  # (n, 2) the exit direction's x, y in the air for TOP exits, else 0


def _hg_sample(mi, dr, d, g: float, u1, u2):
    """Henyey–Greenstein: new direction at angle θ to d with
    cos θ = (1 + g² − ((1 − g²)/(1 − g + 2gξ))²)/(2g), uniform azimuth."""
    if abs(g) < 1e-4:
        cos_t = 1.0 - 2.0 * u1
    else:
        sq = (1.0 - g * g) / (1.0 - g + 2.0 * g * u1)
        cos_t = (1.0 + g * g - sq * sq) / (2.0 * g)
    cos_t = dr.clip(cos_t, -1.0, 1.0)
    sin_t = dr.safe_sqrt(1.0 - cos_t * cos_t)
    sin_p, cos_p = dr.sincos(2.0 * dr.pi * u2)
    local = mi.Vector3f(sin_t * cos_p, sin_t * sin_p, cos_t)
    return mi.Frame3f(d).to_world(local)


def _walk_setup(
    mi, dr, volume: Volume, channel: int, total: int, n_photons: int, seed: int, first_point: int
):
    """What every walk starts from: the channel's per-voxel σ_s and σ_t (flattened z, y, x), the
    majorant, each lane's entry point, and one PCG32 stream per global photon number."""
    Float = mi.Float
    sigma_s = Float(np.ascontiguousarray(volume.sigma_s[..., channel]).ravel())
    sigma_t = Float(np.ascontiguousarray(volume.sigma_t[..., channel]).ravel())
    majorant = float(volume.majorant()[channel])
    idx = dr.arange(mi.UInt32, total)
    point = idx // n_photons
    global_id = mi.UInt64(idx) + mi.UInt64(first_point * n_photons)
    initstate = (int(seed) * 0x9E3779B97F4A7C15 + 0x853C49E6748FEA9B) % 2**64
    rng = mi.PCG32(size=total, initstate=mi.UInt64(initstate), initseq=global_id)
    return sigma_s, sigma_t, majorant, point, rng


def _medium_event(
    mi, dr, volume: Volume, sigma_s, sigma_t, majorant: float, gx, gy, depth, collide, rng, direction
):
    """At a tentative collision: real scattering (prob. σ_s/σ̄), absorption (σ_a/σ̄) or a null event.

    ``gx, gy`` are the position from the volume's corner and ``depth`` below its top (mm); returns
    the scatter and absorb masks and the Henyey–Greenstein direction for scattering photons.
    """
    Z, Y, X = volume.shape
    vox = volume.voxel_mm
    ix = dr.clip(mi.Int32(dr.floor(gx / vox)), 0, X - 1)
    iy = dr.clip(mi.Int32(dr.floor(gy / vox)), 0, Y - 1)
    iz = dr.clip(mi.Int32(dr.floor(depth / vox)), 0, Z - 1)
    flat = mi.UInt32((iz * Y + iy) * X + ix)
    s_s = dr.gather(mi.Float, sigma_s, flat, collide)
    s_t = dr.gather(mi.Float, sigma_t, flat, collide)
    xi = rng.next_float32() * majorant
    scatter = collide & (xi < s_s)
    absorb = collide & (xi >= s_s) & (xi < s_t)
    new_dir = _hg_sample(mi, dr, direction, volume.g, rng.next_float32(), rng.next_float32())
    return scatter, absorb, new_dir


def random_walk(
    volume: Volume,
    channel: int,
    entry_xy: np.ndarray,
    n_photons: int,
    *,
    seed: int = 0,
    first_point: int = 0,
    theta_inc_deg: float = 0.0,
    toward_light: tuple[float, float, float] | None = None,
    index_matched: bool = False,
    max_steps: int = 200_000,
) -> WalkResult:
    """Trace ``n_photons`` photons from each entry point through the slab, in one wavefront.

    Parameters
    ----------
    volume : Volume
        The slab.
    channel : int
        Colour channel (0, 1, 2) whose coefficients are used.
    entry_xy : ndarray, shape (P, 2)
        Entry points on the top face, mm.
    n_photons : int
        Photons per entry point.
    seed : int
        Seed of the PCG32 streams.
    first_point : int
        Global index of ``entry_xy[0]`` (photon streams are numbered globally).
    theta_inc_deg : float
        Angle of incidence from the normal, in the x–z plane (the beam travels toward +x), degrees.
    toward_light : tuple of 3 floats, optional
        In place of ``theta_inc_deg``: the unit direction toward the light (z > 0); the beam flies along
        its opposite and is refracted at the top face.
    index_matched : bool
        Treat the boundary as index-matched (no Fresnel reflection or refraction).
    max_steps : int
        Safety cap on loop iterations per photon; photons still walking are
        reported as ``KILLED``.

    Returns
    -------
    WalkResult
    """
    mi, dr = mitsuba(), drjit()
    Float, UInt32 = mi.Float, mi.UInt32
    total = len(entry_xy) * n_photons
    W, H, T = volume.size_mm
    eta = 1.0 if index_matched else volume.eta

    sigma_s, sigma_t, majorant, point, rng = _walk_setup(
        mi, dr, volume, channel, total, n_photons, seed, first_point
    )

    # -- entry: Fresnel at the top face, then refraction (Snell) -----------------------
    F_in, d0 = _entry(mi, eta, theta_inc_deg, toward_light)
    pos, direction, code = _launch(mi, dr, rng, point, entry_xy, F_in, d0)
    steps = UInt32(0)
    inf = Float(dr.inf)

    def body(pos, direction, rng, code, steps):
        # tentative free-flight distance against the majorant (mm)
        t = -dr.log(1.0 - rng.next_float32()) / majorant
        tx, ty, tz, t_face = _face_distances(dr, pos, direction, W, H, T, inf)  # to the box's faces
        collide = t < t_face

        # -- inside: real or null collision at pos + t d ------------------------------------
        p_c = pos + direction * t
        scatter, absorb, new_dir = _medium_event(
            mi, dr, volume, sigma_s, sigma_t, majorant, p_c.x, p_c.y, -p_c.z, collide, rng, direction
        )

        # -- boundary: Fresnel reflection or exit at the nearest face --------------------
        on_z, reflect, leave, p_b, refl_dir = _face_event(
            mi, dr, rng, pos, direction, tx, ty, tz, t_face, collide, eta
        )
        pos = dr.select(collide, p_c, p_b)
        pos = mi.Vector3f(dr.clip(pos.x, 0.0, W), dr.clip(pos.y, 0.0, H), dr.clip(pos.z, -T, 0.0))
        direction = dr.select(scatter, new_dir, dr.select(reflect, refl_dir, direction))
        top = leave & on_z & (direction.z > 0)
        code = dr.select(absorb, UInt32(ABSORBED), code)
        code = dr.select(leave, dr.select(top, UInt32(TOP), UInt32(OTHER_FACE)), code)
        steps = steps + 1
        code = dr.select((code == ACTIVE) & (steps >= max_steps), UInt32(KILLED), code)
        return pos, direction, rng, code, steps

    pos, direction, rng, code, steps = dr.while_loop(
        state=(pos, direction, rng, code, steps), cond=_walking, body=body, label="photon_walk"
    )
    return _slab_result(dr, pos, direction, code, steps, eta)


def _walking(pos, direction, rng, code, steps):
    """The loop's condition: the photons still walking."""
    return code == ACTIVE


def _entry(mi, eta: float, theta_inc_deg: float, toward_light):
    """Fresnel's reflected share at the top face and the refracted direction in (Snell, 1 → η)."""
    Float = mi.Float
    if toward_light is None:  # from −x in the x–z plane
        th = np.radians(theta_inc_deg)
        toward_light = (-np.sin(th), 0.0, np.cos(th))
    w = np.asarray(toward_light, dtype=np.float64)
    cos_in = float(w[2])
    F_in = float(mi.fresnel(Float(cos_in), Float(eta))[0][0]) if eta != 1.0 else 0.0
    t_x, t_y = (0.0 - w[0]) / eta, (0.0 - w[1]) / eta  # Snell: the travel's tangential part shrinks by 1/η
    d0 = mi.Vector3f(float(t_x), float(t_y), -float(np.sqrt(1.0 - t_x**2 - t_y**2)))
    return F_in, d0


def _launch(mi, dr, rng, point, entry_xy: np.ndarray, F_in: float, d0):
    """The photons' first state: at their entry points (mm) on the top face, along ``d0``, or specular."""
    Float, UInt32 = mi.Float, mi.UInt32
    specular = rng.next_float32() < F_in
    ex = dr.gather(Float, Float(entry_xy[:, 0].astype(np.float32)), point)
    ey = dr.gather(Float, Float(entry_xy[:, 1].astype(np.float32)), point)
    pos = mi.Vector3f(ex, ey, Float(0.0))
    direction = mi.Vector3f(d0)
    code = dr.select(specular, UInt32(TOP + 100), UInt32(ACTIVE))  # 101: specular, kept apart
    return pos, direction, code


def _face_distances(dr, pos, direction, W: float, H: float, T: float, inf):
    """The distances (mm) along ``direction`` to the box's x, y and z faces (inf: parallel), and the least."""
    tx = dr.select(
        direction.x > 0, (W - pos.x) / direction.x, dr.select(direction.x < 0, -pos.x / direction.x, inf)
    )
    ty = dr.select(
        direction.y > 0, (H - pos.y) / direction.y, dr.select(direction.y < 0, -pos.y / direction.y, inf)
    )
    tz = dr.select(
        direction.z > 0, -pos.z / direction.z, dr.select(direction.z < 0, (-T - pos.z) / direction.z, inf)
    )
    t_face = dr.maximum(dr.minimum(dr.minimum(tx, ty), tz), 0.0)
    return tx, ty, tz, t_face


def _face_event(mi, dr, rng, pos, direction, tx, ty, tz, t_face, collide, eta: float):
    """At the nearest face: Fresnel reflection (one draw) or exit; the face, the point and the mirror."""
    Float = mi.Float
    hit = ~collide
    on_z = (tz <= tx) & (tz <= ty)
    on_x = ~on_z & (tx <= ty)
    on_y = ~on_z & ~on_x
    cos_i = dr.abs(dr.select(on_z, direction.z, dr.select(on_x, direction.x, direction.y)))
    if eta != 1.0:
        F = mi.fresnel(-cos_i, Float(eta))[0]  # negative cosine: incident from inside
    else:
        F = Float(0.0)
    reflect = hit & (rng.next_float32() < F)
    leave = hit & ~reflect
    p_b = pos + direction * t_face
    refl_dir = mi.Vector3f(
        dr.select(on_x, -direction.x, direction.x),
        dr.select(on_y, -direction.y, direction.y),
        dr.select(on_z, -direction.z, direction.z),
    )
    return on_z, reflect, leave, p_b, refl_dir


def _slab_result(dr, pos, direction, code, steps, eta: float) -> WalkResult:
    """The walk's end as NumPy: codes (specular −1), exit points (mm), steps and the exits' directions."""
    dr.eval(pos, direction, code, steps)
    code_np = np.asarray(code).astype(np.int64)
    code_np[code_np == TOP + 100] = -1
    # cosine of the outgoing direction to +z for TOP exits (radiance tallies need it):
    # Snell's law refracts the inside cosine c to sqrt(1 - η²(1 - c²)) outside
    c_in = np.where(code_np == TOP, np.asarray(direction.z, dtype=np.float64), 0.0)
    cos_exit = np.where(code_np == TOP, np.sqrt(np.clip(1.0 - eta**2 * (1.0 - c_in**2), 0.0, 1.0)), 0.0)
    top = (code_np == TOP)[:, None]  # the tangential part of the direction grows by η on the way out
    exit_xy = np.where(top, eta * np.stack([np.asarray(direction.x), np.asarray(direction.y)], axis=1), 0.0)
    return WalkResult(
        code=code_np,
        x=np.asarray(pos.x),
        y=np.asarray(pos.y),
        steps=int(dr.sum(steps)[0]),
        cos_exit=cos_exit,
        exit_xy=exit_xy,
    )


def check_memory(n_photons_batch: int, volume: Volume, limit_bytes: float) -> None:
    """Refuse a batch whose estimated memory exceeds ``limit_bytes``."""
    need = n_photons_batch * 96 + volume.nbytes() * 2
    if need > limit_bytes:
        raise TranslucencyError(
            f"photons: a batch needs about {need / 2**30:.1f} GiB, more than the "
            f"{limit_bytes / 2**30:.1f} GiB allowed; lower chunk_points or photons, or the volume's size "
            "(voxel)"
        )
