r"""The light arriving at a fitted object's vertices from the whole scene: every emitter, shadows of
every shape, and the indirect light of the other shapes (and of the glowing objects themselves).

Per vertex v (position :math:`x_v` in scene units, outward normal :math:`n_v`) the effective irradiance is

.. math:: E_v = \int_{H^2} L_i(x_v, \omega)\, \cos\theta\, F_v(\cos\theta)\, T(\cos\theta)\, d\omega,

:math:`L_i` the radiance arriving from the scene (:func:`translucency.scene.integrator.trace`),
:math:`F_v` the incidence law's factor (:mod:`translucency.model.incidence`; 1 for the ``normal`` law)
and :math:`T = F_t(\cos\theta)/F_t(1)` the dielectric boundary's transmittance against the data's normal
beam (1 where index-matched, as :func:`translucency.render.irradiance.vertex_irradiance`).
It is estimated with K samples per vertex and three strategies combined by multiple importance sampling
(power heuristic): next-event estimation toward one Mitsuba emitter, toward one point of the glowing
surfaces, and a cosine-distributed direction whose ray is traced through the scene:

.. math:: \hat E_v = \frac{1}{K} \sum_{k} \sum_{s} w_s\, \frac{L_i(\omega_{ks}) \cos\theta_{ks}\,
          F_v T}{p_s(\omega_{ks})}.

The Dr.Jit kernel returns each sample's :math:`w_s L_i \cos / p_s` and cosine; the per-vertex, per-channel
factor :math:`F_v T` is applied in NumPy (the incidence law is tabulated there).  With ``moment`` (a function
f of the direction toward the light and the normal) the same samples also give the irradiance-weighted mean
:math:`\int E(\omega) f(\omega)\, d\omega / E` (grey: the channels' mean) — the lean's mean vector of the
light arriving from the whole scene (:func:`translucency.render.lean.light_lean`).
"""

from __future__ import annotations

import numpy as np

from ..mitsuba import drjit, load_plugin, mitsuba
from ..model.boundary import fresnel_transmittance
from .integrator import _mis, trace

#: the most paths one wavefront holds: larger ones are traced in batches of samples (a wavefront of a few
#: million paths outgrows the caches and runs slower per path: measured 2.7 against 0.5 µs a path)
WAVEFRONT = 1 << 19


def scene_irradiance(
    scene,
    glow,
    points: np.ndarray,
    normals: np.ndarray,
    *,
    samples: int = 32,
    seed: int = 0,
    incidence=None,
    eta: float = 1.0,
    max_depth: int = 8,
    offset: float | None = None,
    moment=None,
):
    """Effective irradiance (V, 3) at ``points`` (V, 3) with outward ``normals`` (V, 3), scene units;
    with ``moment`` (``f(w (M, 3), n (M, 3)) -> (M, k)``) also the irradiance-weighted mean of f over the
    arriving light, (V, k) (0 where none arrives): ``(E, mean)``.

    ``incidence``: the object's incidence law (``factor(cos (V, K)) -> (V, K, 3)`` or None);
    ``eta``: its boundary (≠ 1: the Fresnel ratio); ``glow``: the fitted objects as they glow now
    (:class:`~translucency.scene.surfaces.GlowingSurfaces`); ``offset``: how far above the surface the
    rays start (default 5·10⁻⁴ of the points' extent).
    """
    points = np.asarray(points, dtype=np.float64)
    normals = np.asarray(normals, dtype=np.float64)
    V, K = len(points), int(samples)
    if offset is None:
        offset = 5e-4 * float(np.max(np.ptp(points, axis=0)) or 1.0)
    # batches of samples, each a wavefront of at most WAVEFRONT paths (whole vertices' worth)
    per_batch = max(1, min(K, WAVEFRONT // max(V, 1)))
    E, done = np.zeros((V, 3)), 0
    num, den = 0.0, np.zeros((V, 1))  # the moment's weighted sums
    while done < K:
        k = min(per_batch, K - done)
        e, parts = _irradiance_batch(
            scene, glow, points, normals, k, (seed * 7919 + done) % 2**32, incidence, eta, max_depth, offset
        )
        E += k * e
        if moment is not None:  # Σ over the samples of every strategy of grey(e_s) f(ω_s)
            n_k = np.repeat(normals, k, axis=0)  # (V k, 3): each sample's normal
            for w, weight in parts:
                grey = weight.mean(axis=2).reshape(-1)  # (V k,)
                safe = np.where((grey > 0)[:, None], w.reshape(-1, 3), n_k)  # (no direction: the normal)
                f = np.asarray(moment(safe, n_k), np.float64)
                num = num + (grey[:, None] * f).reshape(V, k, -1).sum(axis=1)
                den += grey.reshape(V, k).sum(axis=1)[:, None]
        done += k
    if moment is None:
        return E / K
    return E / K, np.divide(num, den, out=np.zeros(np.shape(num)), where=den > 0)


def _irradiance_batch(scene, glow, points, normals, K, seed, incidence, eta, max_depth, offset):
    """:func:`scene_irradiance` with K samples per vertex in one wavefront."""
    mi, dr = mitsuba(), drjit()
    V = len(points)
    N = V * K
    sampler = load_plugin({"type": "independent", "sample_count": 1})
    sampler.seed(seed, N)
    v = dr.arange(mi.UInt32, N) // K
    n = dr.gather(mi.Vector3f, mi.Float(normals.astype(np.float32).ravel()), v)
    p = dr.gather(mi.Point3f, mi.Float((points + offset * normals).astype(np.float32).ravel()), v)
    si = dr.zeros(mi.SurfaceInteraction3f, N)
    si.p, si.n, si.sh_frame, si.t = p, n, mi.Frame3f(n), mi.Float(0.0)
    si.wi = mi.Vector3f(0.0, 0.0, 1.0)
    it = mi.Interaction3f(si)
    active = dr.full(mi.Bool, True, N)
    # 1. one Mitsuba emitter
    ds, em_weight = scene.sample_emitter_direction(it, sampler.next_2d(), True, active)
    cos_e = dr.dot(ds.d, n)
    ok = (cos_e > 0) & (ds.pdf != 0)
    w = dr.select(ds.delta, 1.0, _mis(ds.pdf, dr.maximum(cos_e, 0.0) * dr.inv_pi))
    e_emitter = dr.select(ok, em_weight * w * cos_e, 0.0)
    # 2. one point of the glowing surfaces (none glow before the first transport pass)
    s1, s2 = sampler.next_1d(), sampler.next_2d()
    e_glow, cos_g = dr.zeros(mi.Color3f, N), dr.zeros(mi.Float, N)
    if glow.emitting:
        d, dist, g_weight, g_pdf, valid = glow.sample(p, s1, s2, active)
        cos_g = dr.dot(d, n)
        ok = valid & (cos_g > 0)
        ok &= ~scene.ray_test(it.spawn_ray_to(p + d * dist), ok)
        w = _mis(g_pdf, dr.maximum(cos_g, 0.0) * dr.inv_pi)
        e_glow = dr.select(ok, g_weight * w * cos_g, 0.0)
    # 3. a cosine-distributed direction, its ray traced through the scene (hits weighted against 1 and 2)
    local = mi.warp.square_to_cosine_hemisphere(sampler.next_2d())
    cos_b = local.z
    ray = it.spawn_ray(mi.Frame3f(n).to_world(local))
    L = trace(
        scene,
        sampler,
        glow,
        ray,
        mi.Color3f(1.0),
        it,
        cos_b * dr.inv_pi,
        dr.full(mi.Bool, False, N),
        active & (cos_b > 0),
        max_depth=max_depth,
    )
    e_bsdf = L * dr.pi
    d_bsdf = ray.d
    d_glow = d if glow.emitting else dr.zeros(mi.Vector3f, N)
    dr.eval(e_emitter, cos_e, e_glow, cos_g, e_bsdf, cos_b, ds.d, d_glow, d_bsdf)
    E = np.zeros((V, 3))
    parts = []  # each strategy's directions toward the light (V, K, 3) and weights (V, K, 3)
    for e, c, d_s in ((e_emitter, cos_e, ds.d), (e_glow, cos_g, d_glow), (e_bsdf, cos_b, d_bsdf)):
        e = np.asarray(e, dtype=np.float64).T.reshape(V, K, 3)  # Dr.Jit's (3, N) to (V, K, 3)
        c = np.clip(np.asarray(c, dtype=np.float64).reshape(V, K), 0.0, 1.0)
        factor = fresnel_transmittance(c, eta) / fresnel_transmittance(1.0, eta)
        F = None if incidence is None else incidence.factor(c)
        weight = factor[..., None] if F is None else factor[..., None] * F
        E += (e * weight).mean(axis=1)
        parts.append((np.asarray(d_s, dtype=np.float64).T.reshape(V, K, 3), e * weight))
    return E, parts
