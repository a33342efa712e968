r"""The scene's path tracer: Mitsuba's surfaces and emitters, and fitted objects that glow with their
subsurface exitance.

Estimator (one path per sample; :math:`\beta` the throughput, :math:`p_b` the BSDF's solid-angle density,
:math:`p_e` a Mitsuba emitter's, :math:`p_g` the glowing surfaces', power heuristic
:math:`w(a, b) = a^2/(a^2 + b^2)`): at every vertex :math:`x_k` of the path

.. math:: L \mathrel{+}= \beta\, \bigl[ w(p_b, p_e)\, L_e(x_k) + w(p_b, p_g)\, L_g(x_k) \bigr]
          + \beta\, \Bigl[ w(p_e, p_b)\, \frac{f \cos\, L_e V}{p_e}
                         + w(p_g, p_b)\, \frac{f \cos\, L_g V}{p_g} \Bigr],

the first bracket what the BSDF-sampled ray hit (a Mitsuba emitter :math:`L_e`, or a fitted object's
surface :math:`L_g`, :class:`~translucency.scene.surfaces.GlowingSurfaces`), the second next-event
estimation towards one Mitsuba emitter (``scene.sample_emitter_direction``) and one point of the glowing
surfaces, each with its visibility V.  After a delta bounce (and for the camera ray) hits count with
weight 1.  A path that reaches a fitted object ends there, except for the reflection off its boundary:
the light that crosses the boundary is what the subsurface model accounts for.  The boundary is the
object's ``coat`` (a smooth ``dielectric`` or a ``roughdielectric`` of its η) or none (index-matched,
nothing reflected); a sampled transmission ends the path, and next-event estimation from the coat takes
the reflection side only.

``strategy`` keeps one side only — ``"light"`` (next-event estimation alone; BSDF-sampled hits count
only after delta bounces) or ``"bsdf"`` (BSDF sampling alone) — for the test that both give the same
picture; the default ``"mis"`` combines them.  Russian roulette from ``rr_depth`` on.

The loop is one Dr.Jit ``while_loop`` over a wavefront of paths with masks (no per-path branches).
Units: the scene's; radiance in the emitters' units.
"""

from __future__ import annotations

from functools import lru_cache

from ..mitsuba import drjit, mitsuba

#: the strategies of :func:`trace` (module docstring)
STRATEGIES = ("mis", "light", "bsdf")


def _mis(a, b):
    """Power heuristic :math:`a^2/(a^2 + b^2)`: 1 where b = 0 or a alone is infinite, 0 where both are 0
    or either is no number (a degenerate pair: a ray that met its own start)."""
    dr = drjit()
    a2, b2 = a * a, b * b
    w = a2 / (a2 + b2)
    w = dr.select(dr.isinf(a2) & dr.isfinite(b2), 1.0, w)
    return dr.select(dr.isfinite(w), w, 0.0)


def trace(
    scene,
    sampler,
    glow,
    ray,
    beta,
    prev_si,
    prev_pdf,
    prev_delta,
    active,
    *,
    max_depth: int = 8,
    rr_depth: int = 5,
    strategy: str = "mis",
    sources: str = "all",
):
    r"""Radiance arriving along ``ray`` (a wavefront), by the estimator of the module docstring.

    ``beta`` multiplies the result's paths (1 for a camera ray); ``prev_si``, ``prev_pdf``,
    ``prev_delta`` describe the vertex the ray left (its interaction, the solid-angle density the ray's
    direction was drawn with, whether that was a delta choice), for the weights of what the ray hits.
    ``glow``: the fitted objects (:class:`~translucency.scene.surfaces.GlowingSurfaces`).
    ``sources="glow"``: the glowing surfaces' light alone (the Mitsuba emitters' :math:`L_e` terms
    dropped; each remaining term keeps its weight, so the two add up to ``"all"``).
    Returns the radiance (Color3f), ``beta`` included.
    """
    mi, dr = mitsuba(), drjit()
    n = dr.width(active)
    ctx = mi.BSDFContext()
    reflect = mi.BSDFContext(mi.TransportMode.Radiance, mi.BSDFFlags.Reflection)
    coated = any(c is not None for c in glow.coats)

    def eval_pdf(bsdf, si, wo, ok, on_fitted):
        """The BSDF and its density toward ``wo``: a fitted object's coat by its reflection alone."""
        f, pdf = bsdf.eval_pdf(ctx, si, wo, ok & ~on_fitted)
        if coated:
            f_r, pdf_r = bsdf.eval_pdf(reflect, si, wo, ok & on_fitted)
            f, pdf = dr.select(on_fitted, f_r, f), dr.select(on_fitted, pdf_r, pdf)
        return f, pdf

    hits = strategy != "light"  # BSDF-sampled hits of lights count (with MIS unless "bsdf")
    nee = strategy != "bsdf"
    emitters = sources == "all"  # the Mitsuba emitters count (not for the glow alone)
    weigh = strategy == "mis"
    L = dr.zeros(mi.Color3f, n)
    depth = dr.zeros(mi.UInt32, n)
    beta = mi.Color3f(beta)

    def body(sampler, ray, beta, L, depth, prev_si, prev_pdf, prev_delta, active):
        si = scene.ray_intersect(ray, mi.RayFlags.All, False, active)
        # --- what the ray hit: a Mitsuba emitter (or the sky) and a glowing surface
        ds = mi.DirectionSample3f(scene, si, prev_si)
        count = active & (prev_delta | hits)
        w_e = w_g = mi.Float(1.0)
        if weigh:
            w_g = dr.select(prev_delta, 1.0, _mis(prev_pdf, glow.pdf(si, prev_si.p, count & ~prev_delta)))
        if weigh and emitters:
            p_e = scene.pdf_emitter_direction(prev_si, ds, count & ~prev_delta)
            w_e = dr.select(prev_delta, 1.0, _mis(prev_pdf, p_e))
        arriving = w_g * glow.radiance(si, ray.d, count)
        if emitters:
            arriving += w_e * ds.emitter.eval(si, count)
        L = L + dr.select(count, beta * arriving, 0.0)
        # --- the surface: a fitted object keeps only its boundary's reflection
        fitted_k, on_fitted = glow.hit(si, active)
        bsdf = si.bsdf(ray)
        go_on = active & si.is_valid() & (depth + 1 < max_depth)
        for k, coat in enumerate(glow.coats):
            on_k = fitted_k == k
            if coat is None:
                go_on &= ~on_k
            else:
                bsdf = dr.select(on_k, coat, bsdf)
        # --- next-event estimation: one Mitsuba emitter, one point of the glowing surfaces
        smooth = go_on & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
        s2 = sampler.next_2d(active)
        if nee and emitters:
            ds, em_weight = scene.sample_emitter_direction(si, s2, True, smooth)
            wo = si.to_local(ds.d)
            ok = smooth & (ds.pdf != 0) & (~on_fitted | (mi.Frame3f.cos_theta(wo) > 0))
            f, f_pdf = eval_pdf(bsdf, si, wo, ok, on_fitted)
            w = dr.select(ds.delta, 1.0, _mis(ds.pdf, f_pdf)) if weigh else 1.0
            L = L + dr.select(ok, beta * w * f * em_weight, 0.0)
        s1g, s2g = sampler.next_1d(active), sampler.next_2d(active)
        if nee and glow.emitting:
            d, dist, g_weight, g_pdf, valid = glow.sample(si.p, s1g, s2g, smooth)
            wo = si.to_local(d)
            ok = valid & (~on_fitted | (mi.Frame3f.cos_theta(wo) > 0))
            ok &= ~scene.ray_test(si.spawn_ray_to(si.p + d * dist), ok)
            f, f_pdf = eval_pdf(bsdf, si, wo, ok, on_fitted)
            w = _mis(g_pdf, f_pdf) if weigh else 1.0
            L = L + dr.select(ok, beta * w * f * g_weight, 0.0)
        # --- the next direction, by the BSDF
        s1, s2 = sampler.next_1d(active), sampler.next_2d(active)
        bs, bs_weight = bsdf.sample(ctx, si, s1, s2, go_on & ~on_fitted)
        if coated:  # a coat samples its reflection alone, weighted by it (the transmission is the model's)
            bs_r, weight_r = bsdf.sample(reflect, si, s1, s2, go_on & on_fitted)
            bs = dr.select(on_fitted, bs_r, bs)
            bs_weight = dr.select(on_fitted, weight_r, bs_weight)
        go_on &= bs.pdf > 0
        beta = dr.select(go_on, beta * bs_weight, beta)
        prev_si = dr.select(go_on, mi.Interaction3f(si), prev_si)
        prev_pdf = dr.select(go_on, bs.pdf, prev_pdf)
        prev_delta = dr.select(go_on, mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta), prev_delta)
        ray = dr.select(go_on, si.spawn_ray(si.to_world(bs.wo)), ray)
        # --- Russian roulette
        q = dr.minimum(dr.max(beta), 0.95)
        roulette = go_on & (depth + 1 >= rr_depth)
        survive = sampler.next_1d(active) < q
        beta = dr.select(roulette, beta / dr.maximum(q, 1e-8), beta)
        go_on &= ~roulette | survive
        go_on &= dr.max(beta) > 0
        depth = dr.select(active, depth + 1, depth)
        return sampler, ray, beta, L, depth, prev_si, prev_pdf, prev_delta, go_on

    state = (sampler, ray, beta, L, depth, prev_si, prev_pdf, mi.Bool(prev_delta), mi.Bool(active))
    state = dr.while_loop(state, lambda *s: s[-1], body, label="translucency.trace")
    return state[3]


@lru_cache(maxsize=1)
def integrator_class():
    """The Mitsuba integrator class (defined once Mitsuba runs on a variant: it derives from
    ``mi.SamplingIntegrator``)."""
    mi, dr = mitsuba(), drjit()

    class TranslucentPath(mi.SamplingIntegrator):
        """Mitsuba's path tracing with fitted translucent objects as glowing surfaces (module docstring).

        ``glow``: the fitted objects (:class:`~translucency.scene.surfaces.GlowingSurfaces`), set
        before rendering; ``max_depth``, ``rr_depth``, ``strategy`` as in :func:`trace`.
        """

        def __init__(self, props=None):
            props = props if props is not None else mi.Properties()
            super().__init__(props)
            self.max_depth = int(props["max_depth"]) if "max_depth" in props else 8
            self.rr_depth = int(props["rr_depth"]) if "rr_depth" in props else 5
            self.strategy = str(props["strategy"]) if "strategy" in props else "mis"
            self.glow = None

        def sample(self, scene, sampler, ray, medium=None, active=True):
            n = dr.width(ray.o)
            prev_si = dr.zeros(mi.Interaction3f, n)
            L = trace(
                scene,
                sampler,
                self.glow,
                mi.Ray3f(ray),
                mi.Color3f(1.0),
                prev_si,
                dr.full(mi.Float, 1.0, n),
                dr.full(mi.Bool, True, n),
                dr.full(mi.Bool, True, n) & active,
                max_depth=self.max_depth,
                rr_depth=self.rr_depth,
                strategy=self.strategy,
            )
            return L, dr.full(mi.Bool, True, n), []

        def aov_names(self):
            return []

        def to_string(self):
            return f"TranslucentPath[max_depth={self.max_depth}, strategy={self.strategy}]"

    return TranslucentPath
