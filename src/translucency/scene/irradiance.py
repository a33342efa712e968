r"""The light arriving at a fitted object's vertices from the whole scene: every emitter, shadows of
every shape, and the indirect light of the other shapes (and of the glowing objects themselves).

Per vertex v (position :math:`x_v` in scene units, outward normal :math:`n_v`) the effective irradiance is

.. math:: E_v = \int_{H^2} L_i(x_v, \omega)\, \cos\theta\, F_v(\cos\theta)\, T(\cos\theta)\, d\omega,

:math:`L_i` the radiance arriving from the scene (:func:`translucency.scene.integrator.trace`),
:math:`F_v` the incidence law's factor (:mod:`translucency.model.incidence`; 1 for the ``normal`` law)
and :math:`T = F_t(\cos\theta)/F_t(1)` the dielectric boundary's transmittance against the data's normal
beam (1 where index-matched, as :func:`translucency.transport.irradiance.vertex_irradiance`).
It is estimated with K samples per vertex and three strategies combined by multiple importance sampling
(power heuristic): next-event estimation toward one Mitsuba emitter, toward one point of the glowing
surfaces, and a cosine-distributed direction whose ray is traced through the scene:

.. math:: \hat E_v = \frac{1}{K} \sum_{k} \sum_{s} w_s\, \frac{L_i(\omega_{ks}) \cos\theta_{ks}\,
          F_v T}{p_s(\omega_{ks})}.

The whole estimate runs in one Dr.Jit wavefront, the per-vertex, per-channel factor :math:`F_v T`
included (the incidence law's table looked up by
:meth:`~translucency.model.incidence.HalfSpaceIncidence.kernel`); NumPy only averages each vertex's K
samples.  With ``moment`` (a function f of the direction toward the light and the normal) the same
samples also give the irradiance-weighted mean
:math:`\int E(\omega) f(\omega)\, d\omega / E` (grey: the channels' mean) — the lean's mean vector of the
light arriving from the whole scene (:func:`translucency.transport.lean.light_lean`).
"""

from __future__ import annotations

import numpy as np

from ..mitsuba import drjit, load_plugin, mitsuba
from .integrator import _mis, trace

#: the most paths one wavefront holds: larger ones are traced in batches of samples (a wavefront of a few
#: million paths outgrows the caches and runs slower per path: measured 2.7 against 0.5 µs a path)
WAVEFRONT = 1 << 19


def samples_per_wavefront(vertices: int, samples: int) -> int:
    """Samples a vertex traced in one wavefront: batches of whole vertices' samples, each at most
    :data:`WAVEFRONT` paths (at least one sample a vertex)."""
    return max(1, min(int(samples), WAVEFRONT // max(int(vertices), 1)))


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
    sources: str = "all",
):
    """Effective irradiance (V, 3) at ``points`` (V, 3) with outward ``normals`` (V, 3), scene units;
    with ``moment`` (``f(w (M, 3), n (M, 3)) -> (M, k)``) also the irradiance-weighted mean of f over the
    arriving light, (V, k) (0 where none arrives): ``(E, mean)``.

    ``incidence``: the object's incidence law (``factor(cos (V, K)) -> (V, K, 3)`` or None);
    ``eta``: its boundary (≠ 1: the Fresnel ratio); ``glow``: the fitted objects as they glow now
    (:class:`~translucency.scene.surfaces.GlowingSurfaces`); ``offset``: how far above the surface the
    rays start (default 5·10⁻⁴ of the points' extent); ``sources``: ``"all"`` the light of the whole
    scene, ``"glow"`` only what the glowing objects send (directly or by way of other shapes) — the
    part of the irradiance that is linear in their exitance, for the passes after the first
    (:meth:`~translucency.scene.fitted_scene.FittedScene.light`).
    """
    if sources not in ("all", "glow"):
        raise ValueError(f"sources: {sources!r} is not 'all' or 'glow'")
    points = np.asarray(points, dtype=np.float64)
    normals = np.asarray(normals, dtype=np.float64)
    V, K = len(points), int(samples)
    if offset is None:
        offset = 5e-4 * float(np.max(np.ptp(points, axis=0)) or 1.0)
    per_batch = samples_per_wavefront(V, K)
    E, done = np.zeros((V, 3)), 0
    num, den = 0.0, np.zeros((V, 1))  # the moment's weighted sums
    while done < K:
        k = min(per_batch, K - done)
        e, parts = _irradiance_batch(
            scene,
            glow,
            points,
            normals,
            k,
            (seed * 7919 + done) % 2**32,
            incidence,
            eta,
            max_depth,
            offset,
            sources,
            moment is not None,
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


def _irradiance_batch(
    scene, glow, points, normals, K, seed, incidence, eta, max_depth, offset, sources, moment
):
    """:func:`scene_irradiance` with K samples per vertex in one wavefront: (V, 3), and with ``moment``
    each strategy's directions toward the light and weighted samples, (V, K, 3) each."""
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
    F_t1 = 1.0 - float(mi.fresnel(mi.Float(1.0), mi.Float(float(eta)))[0][0]) if eta != 1.0 else 1.0

    def weight(cos):
        """The per-sample factor F_v(cos) T(cos) (module docstring), 0 below the horizon."""
        w = mi.Color3f(dr.select(cos > 0, 1.0, 0.0))
        if eta != 1.0:  # T = F_t(cos)/F_t(1), Mitsuba's unpolarised Fresnel term from outside
            w *= (1.0 - mi.fresnel(dr.clip(cos, 0.0, 1.0), mi.Float(float(eta)))[0]) / F_t1
        return w if factor is None else w * factor(v, cos)

    factor = None if incidence is None else incidence.kernel()
    strategies = []  # (weighted sample, direction toward the light) of each strategy
    # 1. one Mitsuba emitter (none for the glow alone)
    if sources == "all":
        ds, em_weight = scene.sample_emitter_direction(it, sampler.next_2d(), True, active)
        cos_e = dr.dot(ds.d, n)
        ok = (cos_e > 0) & (ds.pdf != 0)
        w = dr.select(ds.delta, 1.0, _mis(ds.pdf, dr.maximum(cos_e, 0.0) * dr.inv_pi))
        strategies.append((dr.select(ok, em_weight * w * cos_e, 0.0) * weight(cos_e), ds.d))
    else:
        sampler.next_2d()  # (the same random numbers for the strategies that follow)
    # 2. one point of the glowing surfaces (none glow before the first transport pass)
    s1, s2 = sampler.next_1d(), sampler.next_2d()
    if glow.emitting:
        d, dist, g_weight, g_pdf, valid = glow.sample(p, s1, s2, active)
        cos_g = dr.dot(d, n)
        ok = valid & (cos_g > 0)
        ok &= ~scene.ray_test(it.spawn_ray_to(p + d * dist), ok)
        w = _mis(g_pdf, dr.maximum(cos_g, 0.0) * dr.inv_pi)
        strategies.append((dr.select(ok, g_weight * w * cos_g, 0.0) * weight(cos_g), d))
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
        sources=sources,
    )
    strategies.append((L * dr.pi * weight(cos_b), ray.d))
    total = strategies[0][0]
    for e, _ in strategies[1:]:
        total = total + e
    dr.eval(total, *(x for pair in strategies for x in pair) if moment else ())
    E = np.asarray(total, dtype=np.float64).T.reshape(V, K, 3).mean(axis=1)  # Dr.Jit's (3, N) per vertex
    if not moment:
        return E, None
    parts = [
        (np.asarray(d, np.float64).T.reshape(V, K, 3), np.asarray(e, np.float64).T.reshape(V, K, 3))
        for e, d in strategies
    ]
    return E, parts
