r"""Fast relighting of a fitted object: irradiance per vertex, then one sparse product per light.

For incident vertex i (area :math:`A_i`, irradiance :math:`E_i`) the light
leaving vertex o is

.. math:: L(x_o) = \frac{1}{\pi} \sum_i A_i\, E_i\, R_d(x_i, x_o)
                 = \bigl(T E\bigr)_o, \qquad
          T_{oi} = \frac{A_i}{\pi}\, \alpha(x_o) \sum_k c_k(x_i)\, e^{d_k(x_i) |x_o - x_i|},

per channel (radiance in W/(mm² sr) per W/mm² of irradiance; the exitance
:math:`\pi L` is what the virtual acquisition tallies, so the exit is taken as
Lambertian).  :math:`T` holds the pairs closer than a truncation radius, found
with a k-d tree — no O(V²) loop — so once it is built a new light costs one
sparse matrix–vector product per channel.

Every vertex needs parameters, not only the fitted incident points: they are
interpolated by inverse-distance weighting of the k nearest incident points
(:func:`vertex_parameters`).  Irradiance (:func:`vertex_irradiance`) comes from
point or directional lights with shadow rays traced by Mitsuba; the boundary is
index-matched here (no Fresnel factor), as in the acquisitions it is compared with.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError


@dataclass(frozen=True)
class PointLight:
    """Isotropic point light: intensity I (W/sr) at ``position`` (mm)."""

    position: tuple
    intensity: float = 1.0e4


@dataclass(frozen=True)
class DirectionalLight:
    """Distant light: irradiance E (W/mm²) on a surface facing it, travelling along ``direction``."""

    direction: tuple
    irradiance: float = 1.0


@dataclass(frozen=True)
class SpotLight:
    """A point light at ``position`` aimed at ``target`` (mm), intensity I (W/sr) inside a cone.

    Mitsuba's falloff: full intensity within ``0.75 cutoff``, falling linearly in angle to 0 at ``cutoff``.
    """

    position: tuple
    target: tuple
    cutoff_deg: float = 20.0
    intensity: float = 1.0e4

    def falloff(self, w_from_light: np.ndarray) -> np.ndarray:
        axis = np.asarray(self.target, float) - np.asarray(self.position, float)
        axis /= np.linalg.norm(axis)
        theta = np.degrees(np.arccos(np.clip(w_from_light @ axis, -1.0, 1.0)))
        inner = 0.75 * self.cutoff_deg
        return np.clip((self.cutoff_deg - theta) / (self.cutoff_deg - inner), 0.0, 1.0)


@dataclass(frozen=True)
class EnvironmentLight:
    """Uniform radiance L (W/(mm² sr)) from every direction (a constant environment)."""

    radiance: float = 0.1
    samples: int = 64  # cosine-weighted visibility rays per vertex


def parse_light(text: str):
    """``point:x,y,z[,I]``, ``directional:dx,dy,dz[,E]``, ``spot:x,y,z,tx,ty,tz,cutoff_deg[,I]`` or ``env:L``.

    Examples
    --------
    >>> parse_light("point:0,0,100,5e3")
    PointLight(position=(0.0, 0.0, 100.0), intensity=5000.0)
    """
    kind, _, rest = text.partition(":")
    try:
        v = [float(x) for x in rest.split(",")]
    except ValueError:
        raise TranslucencyError(f"light: cannot read numbers in {text!r}") from None
    if kind == "point" and len(v) in (3, 4):
        return PointLight(tuple(v[:3]), *(v[3:] or []))
    if kind == "directional" and len(v) in (3, 4):
        d = np.asarray(v[:3])
        if not np.linalg.norm(d) > 0:
            raise TranslucencyError("light: a directional light needs a non-zero direction")
        return DirectionalLight(tuple(d / np.linalg.norm(d)), *(v[3:] or []))
    if kind == "spot" and len(v) in (7, 8) and 0 < v[6] < 90:
        return SpotLight(tuple(v[:3]), tuple(v[3:6]), *v[6:])
    if kind == "env" and len(v) == 1 and v[0] >= 0:
        return EnvironmentLight(v[0])
    raise TranslucencyError("light: expected point:x,y,z[,I], directional:dx,dy,dz[,E], "
                            f"spot:x,y,z,tx,ty,tz,cutoff_deg[,I] or env:L, got {text!r}")


def vertex_irradiance(mesh, scene, light) -> np.ndarray:
    """Irradiance E (W/mm²) at every vertex, with shadows (Mitsuba ``ray_test``).

    Raises a one-line error for a point light inside the object.
    """
    from ..acquire._engine import mitsuba

    mi = mitsuba()
    v = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    if isinstance(light, EnvironmentLight):
        return _environment_irradiance(mi, mesh, scene, light)
    if isinstance(light, (PointLight, SpotLight)):
        p = np.asarray(light.position, dtype=np.float64)
        # inside a closed, outward-oriented surface a ray first meets a face from its back
        probe = scene.ray_intersect(mi.Ray3f(mi.Point3f(*map(float, p)), mi.Vector3f(0.5773, 0.5774, 0.5773)))
        if bool(probe.is_valid()[0]) and float(np.asarray(probe.n.x)[0] * 0.5773 + np.asarray(probe.n.y)[0] * 0.5774 + np.asarray(probe.n.z)[0] * 0.5773) > 0:
            raise TranslucencyError(f"light: the point light at {tuple(p)} mm is inside the object")
        to = p - v
        dist = np.linalg.norm(to, axis=1)
        w = to / dist[:, None]
        E = light.intensity * np.maximum((w * n).sum(1), 0.0) / dist**2
        if isinstance(light, SpotLight):
            E = E * light.falloff(-w)
        t_max = dist
    else:
        w = -np.asarray(light.direction, dtype=np.float64)
        E = light.irradiance * np.maximum(n @ w, 0.0)
        w = np.broadcast_to(w, v.shape)
        t_max = np.full(len(v), 1e7)
    eps = 1e-4 * float(np.max(mesh.extents))
    o = v + n * eps * 5
    ray = mi.Ray3f(mi.Point3f(*(o[:, k].astype(np.float32) for k in range(3))),
                   mi.Vector3f(*(np.ascontiguousarray(w[:, k]).astype(np.float32) for k in range(3))))
    ray.maxt = mi.Float((t_max - 10 * eps).astype(np.float32))
    blocked = np.asarray(scene.ray_test(ray))
    return np.where(blocked | (E <= 0), 0.0, E)


def _environment_irradiance(mi, mesh, scene, light: EnvironmentLight) -> np.ndarray:
    """E = ∫ L V(ω) cos θ dω by cosine-weighted sampling: π L × (fraction of unoccluded rays)."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    K = int(light.samples)
    rng = np.random.default_rng(0)
    u1, u2 = rng.random((2, len(v), K))
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u1)], axis=-1)  # cosine-weighted
    from ..fit.mesh import tangent_frames

    frame = tangent_frames(n)  # rows t, b, n
    w = np.einsum("vkj,vji->vki", local, frame).reshape(-1, 3)
    o = np.repeat(v + n * 5e-4 * float(np.max(mesh.extents)), K, axis=0)
    ray = mi.Ray3f(mi.Point3f(*(o[:, j].astype(np.float32) for j in range(3))),
                   mi.Vector3f(*(np.ascontiguousarray(w[:, j]).astype(np.float32) for j in range(3))))
    open_sky = ~np.asarray(scene.ray_test(ray)).reshape(len(v), K)
    return np.pi * light.radiance * open_sky.mean(axis=1)


def vertex_parameters(model, vertices: np.ndarray, k: int = 4):
    r"""Each vertex's profile as a blend of the k nearest incident points' profiles.

    Inverse-square-distance weights :math:`w_j` (exact at an incident point):
    :math:`P_v(r) = \sum_j w_j P_j(r)`, itself a sum of k·n exponentials —
    so c, d of shape (V, C, k·n) are returned (with the colour scale (V, 3)).
    Blending the profiles, not their parameters: the average of two exponentials'
    rates and amplitudes is a third exponential unlike either.
    """
    from scipy.spatial import cKDTree

    if model.kind != "exponential" or model.n_directions != 1:
        raise TranslucencyError("model: rendering needs an isotropic exponential model (fit with --model iso)")
    k = min(k, model.n_points)
    dist, idx = cKDTree(model.x_i).query(vertices, k=k)
    dist, idx = dist.reshape(len(vertices), k), idx.reshape(len(vertices), k)
    w = 1.0 / np.maximum(dist, 1e-9) ** 2
    exact = dist[:, 0] < 1e-9
    w[exact] = 0.0
    w[exact, 0] = 1.0
    w /= w.sum(1, keepdims=True)
    V, C, n = len(vertices), model.c.shape[1], model.n_terms
    c = (w[:, :, None, None] * model.c[idx][:, :, :, 0]).transpose(0, 2, 1, 3).reshape(V, C, k * n)
    d = model.d[idx][:, :, :, 0].transpose(0, 2, 1, 3).reshape(V, C, k * n)
    if C == 1:  # shared colour: blend the scales with the same weights (exact where one point dominates)
        s = np.einsum("vk,vkc->vc", w, model.colour_scale[idx])
    else:
        s = np.ones((V, 3))
    return c, d, s


def transport_matrices(model, mesh, *, radius: float | None = None, r_min: float | None = None,
                       max_pairs: float = 2.5e7):
    """The sparse matrices T (one per channel, V × V) of the module docstring.

    ``radius`` defaults to the model's 99 % energy radius (largest over points and channels).
    Distances below ``r_min`` (default: half the mean edge length, the fit's exclusion radius)
    are evaluated at ``r_min``: the profiles were fitted from there out, and their steepest
    terms must not be extrapolated to two vertices that happen to lie very close.
    """
    import scipy.sparse as sp
    from scipy.spatial import cKDTree

    v = np.asarray(mesh.vertices, dtype=np.float64)
    V = len(v)
    from ..acquire.mesh import vertex_areas

    area = vertex_areas(mesh)
    c, d, s = vertex_parameters(model, v)
    if radius is None:
        # the 99 % energy radius, or less where the pairs would not fit in memory:
        # pairs ≈ V² π r² / (surface area)
        fit_pairs = np.sqrt(0.5 * max_pairs * mesh.area / (np.pi * V**2))
        rad = float(min(np.max(model.energy_radius(0.99)), fit_pairs))
    else:
        rad = float(radius)
    pairs = cKDTree(v).query_pairs(rad, output_type="ndarray")
    if 2 * len(pairs) + V > max_pairs:
        raise TranslucencyError(f"radius: {rad:.2f} mm gives {2 * len(pairs) + V:,} vertex pairs; lower --radius")
    # both directions of every pair; each vertex with itself below
    i = np.concatenate([pairs[:, 0], pairs[:, 1]])
    o = np.concatenate([pairs[:, 1], pairs[:, 0]])
    r = np.linalg.norm(v[o] - v[i], axis=1)
    if r_min is None:
        e = np.asarray(mesh.edges_unique_length)
        r_min = 0.5 * float(e.mean())
    r = np.maximum(r, r_min)
    alpha = model.alpha.values if len(model.alpha.values) == V else model.alpha.at(v)
    mats = []
    for ch in range(3):
        cc = c[:, min(ch, c.shape[1] - 1)]
        dd = d[:, min(ch, d.shape[1] - 1)]
        prof = np.einsum("pn,pn->p", cc[i], np.exp(dd[i] * r[:, None])) * s[i, ch]
        vals = area[i] / np.pi * alpha[o] * prof
        # the light a vertex sends into its own area, at the profile's value at r_min like the
        # closest pairs (the integral from r = 0 would extrapolate the steepest fitted term)
        diag = area / np.pi * alpha * np.einsum("vn,vn->v", cc, np.exp(dd * r_min)) * s[:, ch]
        mats.append(sp.csr_matrix((np.concatenate([vals, diag]).astype(np.float32),
                                   (np.concatenate([o, np.arange(V)]), np.concatenate([i, np.arange(V)]))),
                                  shape=(V, V)))
    return mats


def relight_vertices(mats, E: np.ndarray) -> np.ndarray:
    """Radiance per vertex (V, 3) for irradiance E (V,) or (V, 3): one sparse product per channel."""
    E = np.asarray(E, dtype=np.float32)
    E = np.repeat(E[:, None], 3, axis=1) if E.ndim == 1 else E
    return np.stack([mats[ch] @ E[:, ch] for ch in range(3)], axis=1)
