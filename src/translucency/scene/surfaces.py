r"""A fitted object's surface as a light source of the scene: its exitance per vertex, evaluated and sampled.

The subsurface transport (:mod:`translucency.transport.matrices`) gives every vertex v of a fitted object
its exitance :math:`M_v` (W per scene-unit², RGB).  Leaving through the boundary it becomes the radiance

.. math:: L(x, \omega_o) = \frac{1}{\pi} \sum_{j=0}^{2} b_j\, M_{v_j}\, g_{v_j}(\mu_o),
          \qquad \mu_o = n(x) \cdot \omega_o > 0,

on the triangle :math:`(v_0, v_1, v_2)` hit at barycentrics :math:`b`, with the exit's angular law
:math:`g_v(\mu)` normalised to :math:`2\int_0^1 g\,\mu\,d\mu = 1` (Lambertian: g = 1; a dielectric
boundary: :math:`F_t(\mu)/(1 - F_{dr,e})`; the half-space incidence law: :math:`F(\mu)/\langle F\rangle`),
tabulated per vertex at :data:`EXIT_NODES` cosines and interpolated linearly.

:class:`GlowingSurfaces` holds every fitted object of a scene as Dr.Jit arrays and answers the two
questions of a path tracer: *what radiance does a ray that hit it see* (:meth:`GlowingSurfaces.radiance`)
and *which point of it should a shading point sample* (:meth:`GlowingSurfaces.sample`: a triangle in
proportion to its area times its mean exitance, a uniform point in it), with the solid-angle density
of that choice for multiple importance sampling (:meth:`GlowingSurfaces.pdf`).  This replaces Mitsuba's
``area`` emitter with a ``mesh_attribute`` radiance, whose position sampling evaluates the attribute at
a point without a triangle (the texture is not marked spatially varying), which biases next-event
estimation from other surfaces.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..mitsuba import drjit, mitsuba
from .smooth import OneRing

#: cosines at which each vertex's exit law is tabulated (uniform over [0, 1])
EXIT_NODES = 17


@dataclass
class Glowing:
    """One fitted object's surface in scene units: the Mitsuba shape it is, its triangles and per-vertex
    exitance (V, 3) and exit law (V, EXIT_NODES, 3)."""

    shape: object  # the Mitsuba shape (a mesh) the object is in the scene
    vertices: np.ndarray  # (V, 3) scene units
    faces: np.ndarray  # (F, 3)
    exitance: np.ndarray = field(default=None)  # (V, 3) M per scene-unit² per unit irradiance's units
    exit_law: np.ndarray = field(default=None)  # (V, EXIT_NODES, 3): g_v(μ_j), μ_j = j / (EXIT_NODES − 1)
    coat: object = None  # the boundary's Mitsuba BSDF (dielectric or roughdielectric), None: index-matched
    normals: np.ndarray = field(default=None)  # (V, 3) outward vertex normals (for the smooth drawing)

    def __post_init__(self):
        V = len(self.vertices)
        if self.exitance is None:
            self.exitance = np.zeros((V, 3))
        if self.exit_law is None:
            self.exit_law = np.ones((V, EXIT_NODES, 3))

    @property
    def triangle_areas(self) -> np.ndarray:
        """(F,) areas of the triangles, scene units²."""
        p = self.vertices[self.faces]
        return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)


def _floats(array):
    """A NumPy array as a flat Dr.Jit ``Float`` (None stays None)."""
    return None if array is None else mitsuba().Float(np.asarray(array, np.float32).ravel())


def exit_table(law_at) -> np.ndarray:
    """The exit law tabulated at :data:`EXIT_NODES` cosines: ``law_at(mu)`` gives g (V, 3) for one
    cosine; returns (V, EXIT_NODES, 3)."""
    mu = np.linspace(0.0, 1.0, EXIT_NODES)
    return np.stack([np.asarray(law_at(m), dtype=np.float64) for m in mu], axis=1)


class GlowingSurfaces:
    """Every fitted object of a scene as a light: radiance on hit, sampling and its density (module
    docstring).  Built from :class:`Glowing` records; :meth:`update` takes new exitances."""

    def __init__(self, objects: list[Glowing], *, smooth: bool = True):
        mi, dr = mitsuba(), drjit()
        self.objects = list(objects)
        self.pointers = [mi.ShapePtr(o.shape) for o in self.objects]
        self.coats = [None if o.coat is None else mi.BSDFPtr(o.coat) for o in self.objects]
        self._faces = [mi.UInt32(np.asarray(o.faces, np.uint32).ravel()) for o in self.objects]
        self._positions = [mi.Float(np.asarray(o.vertices, np.float32).ravel()) for o in self.objects]
        self._normals = [_floats(o.normals) for o in self.objects]
        counts = [len(o.faces) for o in self.objects]
        self._offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        self._areas = (
            np.concatenate([o.triangle_areas for o in self.objects]) if self.objects else np.zeros(0)
        )
        self._area_array = mi.Float(self._areas.astype(np.float32))
        self._dr = dr
        self.smooth = smooth
        self._rings = [
            OneRing(o.vertices, o.faces, o.normals) if smooth and o.normals is not None else None
            for o in self.objects
        ]
        self.update()

    def update(self) -> None:
        """Take each object's current ``exitance`` and ``exit_law`` (after a new transport pass)."""
        mi = mitsuba()
        self._M = [mi.Float(np.maximum(o.exitance, 0.0).astype(np.float32).ravel()) for o in self.objects]
        self._G = [
            _floats(ring.gradients(o.exitance))
            if self.smooth and ring is not None and np.any(o.exitance)
            else None
            for o, ring in zip(self.objects, self._rings)
        ]
        self._g = [mi.Float(np.maximum(o.exit_law, 0.0).astype(np.float32).ravel()) for o in self.objects]
        # triangles drawn ∝ area × mean exitance (luminance); none: nothing to sample
        power = [
            (np.asarray(o.exitance, np.float64) @ np.array([0.2126, 0.7152, 0.0722]))[o.faces].mean(axis=1)
            for o in self.objects
        ]
        power = (np.concatenate(power) if power else np.zeros(0)) * self._areas
        self.emitting = bool(np.isfinite(power).all() and power.sum() > 0)
        self._distribution = (
            mi.DiscreteDistribution(mi.Float(power.astype(np.float32))) if self.emitting else None
        )

    # ------------------------------------------------------------------ evaluation on the surface
    def _vertex_radiance(self, k: int, v, mu, active, x=None):
        r""":math:`M_v\, g_v(\mu) / \pi` of object k at vertices ``v`` (UInt32) and cosines ``mu``; with
        ``x`` (a point of a triangle of v) the exitance is v's limited linear reconstruction there."""
        mi, dr = mitsuba(), self._dr
        M = dr.gather(mi.Color3f, self._M[k], v, active)
        if x is not None and self._G[k] is not None:
            offset = x - dr.gather(mi.Point3f, self._positions[k], v, active)
            for c in range(3):
                grad = dr.gather(mi.Vector3f, self._G[k], 3 * v + c, active)
                M[c] = dr.maximum(M[c] + dr.dot(grad, offset), 0.0)
        t = dr.clip(mu, 0.0, 1.0) * (EXIT_NODES - 1)
        j0 = dr.minimum(mi.UInt32(t), EXIT_NODES - 2)
        f = t - mi.Float(j0)
        g0 = dr.gather(mi.Color3f, self._g[k], v * EXIT_NODES + j0, active)
        g1 = dr.gather(mi.Color3f, self._g[k], v * EXIT_NODES + j0 + 1, active)
        return M * dr.lerp(g0, g1, f) * dr.inv_pi

    def _triangle(self, k: int, prim, active):
        dr, mi = self._dr, mitsuba()
        return [dr.gather(mi.UInt32, self._faces[k], 3 * prim + j, active) for j in range(3)]

    def _interpolate(self, k: int, triangle, b1, b2, x, mu, active):
        """Radiance of object k at the point ``x`` of the triangle with vertices ``triangle`` (three UInt32),
        barycentrics (1 − b1 − b2, b1, b2), cosine ``mu``: the three vertices' values blended linearly, or
        (``smooth``) their limited linear reconstructions at x (:mod:`translucency.scene.smooth`)."""
        v0, v1, v2 = triangle
        x = x if self.smooth else None
        return (
            (1.0 - b1 - b2) * self._vertex_radiance(k, v0, mu, active, x)
            + b1 * self._vertex_radiance(k, v1, mu, active, x)
            + b2 * self._vertex_radiance(k, v2, mu, active, x)
        )

    def hit(self, si, active):
        """(which, mask): the index of the fitted object ``si`` lies on (−1: none) and whether it is one."""
        mi, dr = mitsuba(), self._dr
        which = dr.full(mi.Int32, -1, dr.width(si.t))
        for k, ptr in enumerate(self.pointers):
            which = dr.select(active & si.is_valid() & (si.shape == ptr), k, which)
        return which, which >= 0

    def radiance(self, si, ray_d, active):
        r"""Radiance toward :math:`-\omega` = ``-ray_d`` leaving the fitted object at ``si`` (0 off them and
        from their inside).  The exit law's cosine is taken against the shading normal (the vertex normals
        interpolated), so that the law does not jump at the mesh's edges."""
        mi, dr = mitsuba(), self._dr
        out = dr.zeros(mi.Color3f, dr.width(si.t))
        outside = -dr.dot(si.n, ray_d) > 0
        mu = dr.maximum(-dr.dot(si.sh_frame.n, ray_d), 0.0)
        for k, ptr in enumerate(self.pointers):
            on = active & si.is_valid() & (si.shape == ptr) & outside
            triangle = self._triangle(k, si.prim_index, on)
            value = self._interpolate(k, triangle, si.uv.x, si.uv.y, si.p, mu, on)
            out = dr.select(on, value, out)
        return out

    def pdf(self, si, ray_o, active):
        r"""Solid-angle density, seen from ``ray_o``, with which :meth:`sample` would pick the point ``si``:
        :math:`p_t / A_t \cdot |x - o|^2 / |\cos\theta_x|`."""
        mi, dr = mitsuba(), self._dr
        out = dr.zeros(mi.Float, dr.width(si.t))
        if not self.emitting:
            return out
        d = si.p - ray_o
        dist2 = dr.squared_norm(d)
        cos_x = dr.abs(dr.dot(si.n, dr.normalize(d)))
        for k, ptr in enumerate(self.pointers):
            on = active & si.is_valid() & (si.shape == ptr)
            tri = mi.UInt32(int(self._offsets[k])) + si.prim_index
            pmf = self._distribution.eval_pmf_normalized(tri, on)
            area = dr.gather(mi.Float, self._area_array, tri, on)
            on &= area > 0
            out = dr.select(on, pmf / area * dist2 / dr.maximum(cos_x, 1e-7), out)
        return out

    def sample(self, ref_p, sample1, sample2, active):
        r"""A point of the glowing surfaces seen from ``ref_p``: returns (direction, distance, radiance
        toward ``ref_p`` divided by the solid-angle density, density, valid).

        A triangle t with probability :math:`p_t` ∝ area × mean exitance, a uniform point in it (density
        :math:`p_t/A_t` per area), converted to solid angle by :math:`|x - p|^2/\cos\theta_x`; points
        seen from behind (:math:`\cos\theta_x \le 0`) are invalid.  No visibility test here.
        """
        mi, dr = mitsuba(), self._dr
        n_lanes = dr.width(sample1)
        zero3 = dr.zeros(mi.Vector3f, n_lanes)
        if not self.emitting:
            return (
                zero3,
                dr.zeros(mi.Float, n_lanes),
                dr.zeros(mi.Color3f, n_lanes),
                dr.zeros(mi.Float, n_lanes),
                dr.full(mi.Bool, False, n_lanes),
            )
        tri, pmf = self._distribution.sample_pmf(sample1, active)
        bary = mi.warp.square_to_uniform_triangle(sample2)
        b1, b2 = bary.x, bary.y
        position = dr.zeros(mi.Point3f, n_lanes)
        normal = dr.zeros(mi.Vector3f, n_lanes)
        radiance = dr.zeros(mi.Color3f, n_lanes)
        area = dr.gather(mi.Float, self._area_array, tri, active)
        for k in range(len(self.objects)):
            lo, hi = int(self._offsets[k]), int(self._offsets[k + 1])
            on = active & (tri >= lo) & (tri < hi)
            prim = tri - lo
            v0, v1, v2 = self._triangle(k, prim, on)
            p0, p1, p2 = (dr.gather(mi.Point3f, self._positions[k], v, on) for v in (v0, v1, v2))
            p = (1.0 - b1 - b2) * p0 + b1 * p1 + b2 * p2
            n = dr.normalize(dr.cross(p1 - p0, p2 - p0))
            d = ref_p - p
            shading = n
            if self._normals[k] is not None:  # the exit law's cosine against the interpolated normal
                n0, n1, n2 = (dr.gather(mi.Vector3f, self._normals[k], v, on) for v in (v0, v1, v2))
                shading = dr.normalize((1.0 - b1 - b2) * n0 + b1 * n1 + b2 * n2)
            mu = dr.maximum(dr.dot(shading, dr.normalize(d)), 0.0)
            value = self._interpolate(k, (v0, v1, v2), b1, b2, p, mu, on)
            position = dr.select(on, p, position)
            normal = dr.select(on, n, normal)
            radiance = dr.select(on, value, radiance)
        to = position - ref_p
        dist = dr.norm(to)
        direction = to / dist
        cos_x = -dr.dot(normal, direction)
        valid = active & (cos_x > 0) & (pmf > 0) & (area > 0) & (dist > 0)
        pdf = dr.select(valid, pmf / area * dist * dist / cos_x, 0.0)
        weight = radiance / pdf
        valid &= dr.isfinite(pdf) & (pdf > 0) & dr.all(dr.isfinite(weight))
        weight = dr.select(valid, weight, 0.0)
        return direction, dist, weight, pdf, valid
