r"""Fast relighting of a fitted object: irradiance per vertex, then one sparse product per light.

For incident vertex i (area :math:`A_i`, irradiance :math:`E_i`) the light
leaving vertex o is

.. math:: L(x_o) = \frac{1}{\pi} \sum_i A_i\, E_i\, R_d(x_i, x_o)
                 = \bigl(T E\bigr)_o, \qquad
          T_{oi} = \frac{A_i}{\pi}\, \alpha(x_o) \sum_k c_k(x_i)\, e^{d_k(x_i) |x_o - x_i|},

per channel (radiance in W/(mm² sr) per W/mm² of irradiance; the exitance
:math:`\pi L` is what the virtual acquisition tallies, so the exit is taken as
Lambertian).  :math:`T` holds the pairs closer than a near radius, found
with a k-d tree — no O(V²) loop — and the pairs beyond it go through a
hierarchical far field (clustered sources, a K × K operator, interpolation back to
the vertices: :mod:`translucency.render._far_field`), so once it is built a new light
costs one sparse matrix–vector product per channel and the far field's small products.

Every vertex needs parameters, not only the fitted incident points: they are
interpolated by inverse-distance weighting of the k incident points nearest
along the surface (:func:`vertex_parameters`, :func:`geodesic_neighbours`).  Irradiance
(:func:`vertex_irradiance`) comes from point, spot, directional or environment lights (a constant sky or an
environment map, importance-sampled by Mitsuba's ``envmap`` emitter) with
shadow rays traced by Mitsuba.

**Boundary.**  For an object acquired behind a dielectric boundary (index η)
the measured R_d already holds the transmission of the normally incident
calibration beam, :math:`F_t(0)`, and all light that left; a light arriving at
:math:`\theta_i` is therefore scaled by :math:`F_t(\theta_i)/F_t(0)`
(:func:`vertex_irradiance` with ``eta``), and the exitance leaves with the
angular shape of the transmission,
:math:`L(\theta_o) = M\, F_t(\theta_o) / (\pi (1 - F_{dr,e}))`, normalised so
that it integrates to M (:func:`exit_fresnel`).  Index-matched objects (η = 1)
get neither factor.

**Incidence.**  The data's beams arrive normally; light arriving at :math:`\theta_i` enters
shallower and more of it comes back.  With an incidence law
(:mod:`translucency.model.incidence`, ``half-space`` by default) each arriving direction is weighted
by Chandrasekhar's :math:`F(\cos\theta_i; R_{1,v}) = R(\cos\theta_i)/R(1)` per vertex and channel,
R_1 the vertex's measured total (:attr:`Transport.reflectance`), so the irradiance becomes (V, 3).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numba import njit, prange
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from .._validate import TranslucencyError, plain
from ..geometry import tangent_frames, vertex_areas
from ..mitsuba import drjit, load_plugin, mitsuba, rays
from ..model.boundary import exit_factor, fresnel_transmittance
from ..model.incidence import incidence_law
from ..model.through import through_factor
from ._far_field import FarField, far_field_operator
from .lights import EnvironmentLight, PointLight, SpotLight


def view_cosines(mesh, viewpoint) -> np.ndarray:
    r""":math:`\cos\theta_o` per vertex: its normal against the direction to ``viewpoint`` (mm)."""
    to = np.asarray(viewpoint, dtype=np.float64) - np.asarray(mesh.vertices, dtype=np.float64)
    return np.einsum("vk,vk->v", to, np.asarray(mesh.vertex_normals)) / np.linalg.norm(to, axis=1)


def exit_fresnel(mesh, viewpoint, eta: float) -> np.ndarray:
    r"""Per-vertex factor :math:`F_t(\theta_o)/(1 - F_{dr,e})` toward ``viewpoint`` (1 where η = 1)."""
    if eta == 1.0:
        return np.ones(len(mesh.vertices))
    return exit_factor(view_cosines(mesh, viewpoint), eta)


def vertex_irradiance(mesh, scene, light, eta: float = 1.0, incidence=None, at=None) -> np.ndarray:
    r"""Irradiance E (W/mm²) at every vertex, with shadows (Mitsuba ``ray_test``).

    (V,) for the grey lights, (V, 3) for an environment map or with an incidence law.  With ``eta`` ≠ 1
    each arriving direction is weighted by :math:`F_t(\theta_i)/F_t(0)` (module docstring).
    ``incidence`` (:class:`~translucency.model.incidence.HalfSpaceIncidence`, or None / ``NormalIncidence``:
    none) weights each arriving direction by how much more a point sends back of light arriving at
    :math:`\theta_i` than of the normal incidence its data were measured with, per channel: the
    *effective* irradiance :math:`\int L V \cos\theta_i\, F_v(\cos\theta_i)\, d\omega`
    (:mod:`translucency.model.incidence`).
    ``at``: the vertices (indices) to compute it at (all by default; ``incidence`` then holds those).
    Raises a one-line error for a point light inside the object.
    """
    mi = mitsuba()
    v = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    if at is not None:
        v, n = v[at], n[at]
    if isinstance(light, EnvironmentLight):
        return _environment_irradiance(mi, v, n, float(np.max(mesh.extents)), scene, light, eta, incidence)
    if isinstance(light, (PointLight, SpotLight)):
        p = np.asarray(light.position, dtype=np.float64)
        # inside a closed, outward-oriented surface a ray first meets a face from its back
        probe = scene.ray_intersect(mi.Ray3f(mi.Point3f(*map(float, p)), mi.Vector3f(0.5773, 0.5774, 0.5773)))
        if (
            bool(probe.is_valid()[0])
            and float(
                np.asarray(probe.n.x)[0] * 0.5773
                + np.asarray(probe.n.y)[0] * 0.5774
                + np.asarray(probe.n.z)[0] * 0.5773
            )
            > 0
        ):
            raise TranslucencyError(f"light: the point light at {plain(p)} mm is inside the object")
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
    blocked = np.asarray(scene.ray_test(rays(o, w, t_max - 10 * eps)))
    cos_i = np.einsum("vk,vk->v", w, n)
    E = E * fresnel_transmittance(cos_i, eta) / fresnel_transmittance(1.0, eta)
    E = np.where(blocked | (E <= 0), 0.0, E)
    F = None if incidence is None else incidence.factor(cos_i)  # (V, 3) or None
    return E if F is None else E[:, None] * F


def _environment_irradiance(
    mi, v, n, extent, scene, light: EnvironmentLight, eta: float, incidence
) -> np.ndarray:
    r"""Estimate :math:`E = \int L(\omega) V(\omega) \cos\theta\, F(\cos\theta)\, d\omega` with K rays
    per vertex (F: the incidence law's factor, 1 without one).

    Constant sky: cosine-weighted directions, :math:`E \approx \pi L \langle V F \rangle`.
    Map: directions drawn by the ``envmap`` emitter in proportion to its luminance,
    :math:`E \approx \langle (L/p)\, V \cos^+\theta\, F \rangle` (RGB).
    """
    K = int(light.samples)
    rng = np.random.default_rng(0)
    u1, u2 = rng.random((2, len(v), K))
    o = np.repeat(v + n * 5e-4 * extent, K, axis=0)
    if light.filename is None:
        r, phi = np.sqrt(u1), 2 * np.pi * u2
        local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u1)], axis=-1)  # cosine-weighted
        frame = tangent_frames(n)  # rows t, b, n
        w = np.einsum("vkj,vji->vki", local, frame).reshape(-1, 3)
        weight = np.full((len(w), 1), np.pi * light.radiance)  # L cos / p with p = cos/π
    else:
        emitter = load_plugin(light.emitter_dict())
        it = drjit().zeros(mi.Interaction3f, len(o))
        it.p = mi.Point3f(*(o[:, j].astype(np.float32) for j in range(3)))
        ds, spec = emitter.sample_direction(
            it, mi.Point2f(u1.ravel().astype(np.float32), u2.ravel().astype(np.float32))
        )
        w = np.stack([np.asarray(ds.d.x), np.asarray(ds.d.y), np.asarray(ds.d.z)], axis=1).astype(np.float64)
        weight = np.stack([np.asarray(spec[j]) for j in range(3)], axis=1)  # L / p, times cos⁺ below
    cos_i = np.einsum("vkj,vj->vk", w.reshape(len(v), K, 3), n).reshape(-1)
    if light.filename is not None:
        weight = weight * np.maximum(cos_i, 0.0)[:, None]
    open_sky = ~np.asarray(scene.ray_test(rays(o, w)))
    weight = (
        weight * (open_sky * fresnel_transmittance(cos_i, eta) / fresnel_transmittance(1.0, eta))[:, None]
    )
    weight = weight.reshape(len(v), K, -1)
    F = None if incidence is None else incidence.factor(cos_i.reshape(len(v), K))  # (V, K, 3)
    if F is not None:
        return (weight * F).mean(axis=1)
    E = weight.mean(axis=1)
    return E[:, 0] if light.filename is None else E


def geodesic_neighbours(mesh, sources: np.ndarray, k: int, limit: float | None = None):
    """The k incident vertices nearest to every vertex along the surface.

    Distances are shortest paths over the mesh's edges (Dijkstra, from all
    sources in chunks, up to ``limit`` mm — default three spacings of the
    sources); a vertex reaches fewer than k sources where the others are
    farther or on another piece of the mesh (their distance is inf).

    Returns
    -------
    dist, idx : ndarray, shape (V, k)
        Graph distances (mm, ascending) and indices into ``sources``.
    """
    V, P = len(mesh.vertices), len(sources)
    e = np.asarray(mesh.edges_unique)
    graph = sp.csr_matrix(
        (np.asarray(mesh.edges_unique_length, dtype=np.float64), (e[:, 0], e[:, 1])), shape=(V, V)
    )
    if limit is None:
        limit = 3.0 * np.sqrt(float(mesh.area) / max(P, 1))
    best_d, best_i = np.full((V, k), np.inf), np.zeros((V, k), dtype=np.int64)
    for s in range(0, P, 64):
        D = dijkstra(graph, directed=False, indices=sources[s : s + 64], limit=limit)  # (chunk, V)
        cand_d = np.concatenate([best_d, D.T], axis=1)
        cand_i = np.concatenate([best_i, np.broadcast_to(np.arange(s, s + len(D)), (V, len(D)))], axis=1)
        keep = np.argsort(cand_d, axis=1, kind="stable")[:, :k]
        best_d, best_i = np.take_along_axis(cand_d, keep, 1), np.take_along_axis(cand_i, keep, 1)
    return best_d, best_i


def neighbour_weights(model, vertices, k: int = 4):
    r"""Blend weights of the k incident points nearest each vertex: (w, idx), each (V, k).

    Inverse-square-distance weights :math:`w_j`, normalised, exact (a single 1) at an incident point.
    ``vertices``: positions (V, 3) — nearest in a straight line — or a mesh whose vertices the incident
    points are — nearest along the surface (:func:`geodesic_neighbours`), so that nothing leaks across a
    thin gap between two parts of an object; vertices that reach no incident point that way fall back to
    straight-line distances.
    """
    k = min(k, model.n_points)
    mesh = vertices if hasattr(vertices, "edges_unique") else None
    vertices = np.asarray(mesh.vertices if mesh is not None else vertices, dtype=np.float64)
    dist, idx = cKDTree(model.x_i).query(vertices, k=k)
    dist, idx = dist.reshape(len(vertices), k), idx.reshape(len(vertices), k)
    if mesh is not None:
        gap, src = cKDTree(np.asarray(mesh.vertices)).query(model.x_i)
        if np.all(gap <= 1e-6 * float(np.max(mesh.extents))):  # the incident points are vertices
            g_dist, g_idx = geodesic_neighbours(mesh, src, k)
            reached = np.isfinite(g_dist[:, 0])
            dist[reached], idx[reached] = g_dist[reached], g_idx[reached]
    w = 1.0 / np.maximum(dist, 1e-9) ** 2
    exact = dist[:, 0] < 1e-9
    w[exact] = 0.0
    w[exact, 0] = 1.0
    return w / w.sum(1, keepdims=True), idx


def vertex_parameters(model, vertices, k: int = 4, weights=None):
    r"""Each vertex's profile as a blend of the k nearest incident points' profiles.

    :math:`P_v(r) = \sum_j w_j P_j(r)` with the weights of :func:`neighbour_weights`
    (or ``weights`` = (w, idx) computed before), itself a sum of k·n exponentials —
    so c, d of shape (V, C, k·n) are returned (with the colour scale (V, 3)).
    Blending the profiles, not their parameters: the average of two exponentials'
    rates and amplitudes is a third exponential unlike either.
    """
    if model.kind != "exponential" or model.n_directions != 1:
        raise TranslucencyError(
            "model: rendering needs an isotropic exponential model (fit with --model iso)"
        )
    w, idx = neighbour_weights(model, vertices, k) if weights is None else weights
    V, k = w.shape
    C, n = model.c.shape[1], model.n_terms
    c = (w[:, :, None, None] * model.c[idx][:, :, :, 0]).transpose(0, 2, 1, 3).reshape(V, C, k * n)
    d = model.d[idx][:, :, :, 0].transpose(0, 2, 1, 3).reshape(V, C, k * n)
    if C == 1:  # shared colour: blend the scales with the same weights (exact where one point dominates)
        s = np.einsum("vk,vkc->vc", w, model.colour_scale[idx])
    else:
        s = np.ones((V, 3))
    return c, d, s


#: the most vertex pairs a transport holds (near pairs both ways, plus the diagonal): about 7.5 GB at the
#: measured 240–330 bytes a pair; :func:`default_radius` stays below it and :func:`transport_matrices`
#: refuses beyond it
MAX_PAIRS = 2.5e7
#: alternating column/row scalings of the measured near field (:func:`transport_matrices`, "rows")
BALANCE_STEPS = 4
#: a row's scaling stays within [1 / ROW_LIMIT, ROW_LIMIT]
ROW_LIMIT = 2.0


def default_radius(model, mesh, *, max_pairs: float = MAX_PAIRS) -> float:
    r"""The transport's default near radius (mm): the model's 99 % energy radius, or less where the pairs
    would not fit.

    Pairs within r on a surface of area A with V vertices number about :math:`V^2 \pi r^2 / A`; the radius
    is capped where that reaches half of ``max_pairs``, :math:`r \le \sqrt{p_{max} A / (2 \pi V^2)}`.

    Parameters
    ----------
    model : VertexModel
        Its ``energy_radius(0.99)`` (largest over points and channels) is the wanted radius.
    mesh : trimesh.Trimesh
        The object (its vertices and surface area).
    max_pairs : float
        The pair limit, :data:`MAX_PAIRS` by default.

    Examples
    --------
    >>> r = default_radius(model, mesh)  # doctest: +SKIP
    """
    V = len(mesh.vertices)
    fit_pairs = np.sqrt(0.5 * max_pairs * mesh.area / (np.pi * V**2))
    return float(min(np.max(model.energy_radius(0.99)), fit_pairs))


def transport_matrices(
    model,
    mesh,
    *,
    radius: float | None = None,
    r_min: float | None = None,
    max_pairs: float = MAX_PAIRS,
    far_field: bool = True,
    clusters: int | None = None,
    balance_rows: bool = True,
    through: bool = False,
):
    r"""The sparse transport T of the module docstring, as a :class:`Transport` (one matrix per
    channel, or one matrix and the colour scale for the shared-colour model).

    ``radius`` defaults to the model's 99 % energy radius (largest over points and channels).
    Distances below ``r_min`` (default: half the mean edge length, the fit's exclusion radius)
    are evaluated at ``r_min``: the profiles were fitted from there out, and their steepest
    terms must not be extrapolated to two vertices that happen to lie very close.

    **Near field.**  A model that carries what its acquisition measured (``model.measured``,
    :func:`translucency.fit.mesh.measured_near_field`; blended to every vertex with the profile
    weights) gets its diagonal and its totals from the data:

    .. math:: T_{ii} = \frac{A_i}{\pi}\,\mathrm{own}_i, \qquad
              \sum_{o \ne i} A_o T_{oi} = \frac{A_i}{\pi}\,(\mathrm{total}_i - A_i\,\mathrm{own}_i),

    i.e. the light a vertex sends into its own area is the measured one (the fit never sees it),
    and each column of the spread is scaled so that the kernel carries the measured total
    exitance whatever the local vertex density and the truncation radius.  (Both already hold α.)
    Without it the diagonal is the profile at ``r_min`` and columns are not rescaled.

    **Rows** (``balance_rows``, with a measured near field).  The columns alone conserve each
    source's energy, but what a *receiver* collects is a quadrature of the steep near profile over
    its neighbours' cells, and on a mesh whose cell areas jump (marching cubes: ±35 % between
    neighbours on the pig) it jumps with them — rings on a uniformly lit flank.  By reciprocity of
    the diffuse transport, :math:`R_d(x_i, x_o) = R_d(x_o, x_i)`, a receiver under uniform irradiance
    gathers what it would send as a source, so the rows have the same target as the columns:

    .. math:: \sum_i T_{oi} = \frac{1}{\pi}(\mathrm{total}_o - A_o\,\mathrm{own}_o).

    :math:`T_{oi} = x_o\,K_{oi}\,y_i` is balanced by alternating the two scalings (Sinkhorn;
    ``BALANCE_STEPS``, the last step a column step so that every source's energy holds exactly;
    the row factors x within [1/2, 2]); the far field, smooth, takes the column factors only.

    **Through the body** (``through``, a model whose fit measured the table
    ``model.measured["through"]``, :mod:`translucency.model.through`).  Every pair's profile is multiplied
    by the source's table at the pair's :math:`(n_i \cdot n_o, r)`, blended between incident points with
    the profile weights, before the normalisations; the table is per channel, so the transport holds
    three matrices even for a shared-colour model.  ``through=False`` (the default: the table does not win
    on every case of the objects table, docs/objects.md) or a model without the table is the paper's model.

    **Far field.**  The pairs beyond ``radius`` are not dropped: ``far_field`` (default) adds them
    hierarchically (:mod:`translucency.render._far_field`: ``clusters`` source clusters, K², default
    about 4 · surface / (π radius²), 256 to 3,000, with members opened near the radius; the smooth
    result interpolated back to the vertices), so light that enters one side of a thick body leaves
    the other.  With a measured near field the column normalisation above applies to near and far
    together — each vertex's kernel still carries exactly its measured total; without it the far field
    adds the profile's tail.  ``far_field=False`` truncates at ``radius`` (the ablation).  Memory: the
    near pairs plus K² float32 per matrix (36 MB at K = 3,000) and (k + 1) · V entries.

    Examples
    --------
    >>> T = transport_matrices(model, mesh)  # doctest: +SKIP
    >>> L = relight_vertices(T, E)  # doctest: +SKIP
    """
    v = np.asarray(mesh.vertices, dtype=np.float64)
    V = len(v)
    area = vertex_areas(mesh)
    weights = neighbour_weights(model, mesh)
    c, d, s = vertex_parameters(model, mesh, weights=weights)
    own, total = _measured_per_vertex(model, weights, v, area)
    rad = default_radius(model, mesh, max_pairs=max_pairs) if radius is None else float(radius)
    pairs = cKDTree(v).query_pairs(rad, output_type="ndarray")
    if 2 * len(pairs) + V > max_pairs:
        raise TranslucencyError(
            f"radius: {rad:.2f} mm gives {2 * len(pairs) + V:,} vertex pairs; lower --radius"
        )
    # both directions of every pair; each vertex with itself below
    i = np.concatenate([pairs[:, 0], pairs[:, 1]])
    o = np.concatenate([pairs[:, 1], pairs[:, 0]])
    r = np.linalg.norm(v[o] - v[i], axis=1)
    if r_min is None:
        e = np.asarray(mesh.edges_unique_length)
        r_min = 0.5 * float(e.mean())
    r = np.maximum(r, r_min)
    alpha = model.alpha.values if len(model.alpha.values) == V else model.alpha.at(v)
    # the through-body table blended to every vertex (V, 4, 8, 3), or None: the paper's model
    table = None
    if through and model.measured and "through" in model.measured:
        w_b, idx_b = weights
        table = np.einsum("vk,vkabc->vabc", w_b, model.measured["through"][idx_b])
    # shared colour (one fall-off, C = 1): T_λ = T · diag(s_λ) — one matrix, the scale goes with E
    # (not with the through table: it is per channel)
    shared = c.shape[1] == 1 and table is None
    normals = np.asarray(mesh.vertex_normals, dtype=np.float64)
    cos_io = np.einsum("mk,mk->m", normals[i], normals[o]) if table is not None else None
    # the pairs beyond rad: clusters and their K × K operator, b_i = A_i/π until normalised below
    far = (
        far_field_operator(
            model,
            v=v,
            area=area,
            alpha=alpha,
            weights=weights,
            c=c,
            d=d,
            radius=rad,
            surface=float(mesh.area),
            clusters=clusters,
            through=None if table is None else (table, normals),
        )
        if far_field
        else None
    )
    # (V, 3) the spread's share of each vertex's measured total: the columns' (and rows') target
    tau = None if own is None else np.maximum(total - area[:, None] * own, 0.0)
    mats = []
    for ch in range(1 if shared else 3):
        cc, dd = c[:, min(ch, c.shape[1] - 1)], d[:, min(ch, c.shape[1] - 1)]
        scale = 1.0 if shared else s[:, ch]
        prof = np.einsum("pn,pn->p", cc[i], np.exp(dd[i] * r[:, None])) * (scale if shared else scale[i])
        if table is not None:  # light through the body: the source's table at (n_i · n_o, r)
            prof = prof * through_factor(table[..., ch], i, cos_io, r)
        vals = area[i] / np.pi * alpha[o] * prof
        if own is None:
            # the light a vertex sends into its own area, at the profile's value at r_min like the
            # closest pairs (the integral from r = 0 would extrapolate the steepest fitted term)
            diag = area / np.pi * alpha * np.einsum("vn,vn->v", cc, np.exp(dd * r_min)) * scale
        else:
            # measured own area (kept apart, per channel); the spread of column i normalised to carry
            # 1 (shared colour: the scale below carries each channel's total_i − A_i own_i) or
            # total_i − A_i own_i itself (one matrix per channel)
            target = np.ones(V) if shared else tau[:, ch]
            # what rides with a uniform irradiance through this matrix, and the rows' target (reciprocity)
            rides = tau.mean(axis=1) if shared else np.ones(V)
            row_target = (tau.mean(axis=1) if shared else tau[:, ch]) / np.pi
            far_spread = far.spread(ch, area) if far is not None else 0.0  # near and far carry the total
            x = np.ones(V)  # row factors
            for step in range(BALANCE_STEPS if balance_rows else 1):
                # column step: Σ_o A_o T_oi = A_i/π · target_i
                near = np.bincount(i, weights=area[o] * vals * x[o], minlength=V) * np.pi / area
                spread = near + far_spread
                factor = np.divide(target, spread, out=np.zeros(V), where=spread > 0)
                if step == BALANCE_STEPS - 1 or not balance_rows:
                    break
                # row step: Σ_i T_oi rides_i = row_target_o, the far field's rows held as they are
                near_row = np.bincount(o, weights=vals * (factor * rides)[i], minlength=V)
                far_row = 0.0
                if far is not None:
                    X = np.repeat((factor * rides)[:, None], 3, axis=1).astype(np.float32)
                    far_row = far.apply(X)[:, 0 if shared else ch]
                want = row_target - far_row
                x = np.clip(
                    np.divide(want, near_row, out=np.ones(V), where=(near_row > 0) & (want > 0)),
                    1.0 / ROW_LIMIT,
                    ROW_LIMIT,
                )
            vals = vals * x[o] * factor[i]
            if far is not None:
                far.normalise(ch, factor)
            diag = None  # the own area rides beside the matrix (Transport.own), per channel
        rows, cols = (
            (o, i) if diag is None else (np.concatenate([o, np.arange(V)]), np.concatenate([i, np.arange(V)]))
        )
        data = vals if diag is None else np.concatenate([vals, diag])
        mats.append(sp.csr_matrix((data.astype(np.float32), (rows, cols)), shape=(V, V)))
    if own is None:
        return Transport(matrices=mats, scale=s.astype(np.float32) if shared else None, far=far)
    scale = tau if shared else None
    return Transport(
        matrices=mats,
        scale=None if scale is None else scale.astype(np.float32),
        own=(area[:, None] / np.pi * own).astype(np.float32),
        far=far,
        reflectance=total,
        through=table is not None,
    )


def _measured_per_vertex(model, weights, vertices, area):
    r"""``model.measured``'s own and total (V, 3) at every vertex; (None, None) for a model without them.

    The total exitance blends with the profile weights.  The own-area value does not: R_d(x_i, x_i) is the
    mean over the incident vertex's own cell, so it grows as the cell shrinks toward the peak, and blending
    it across cells of other sizes misplaces energy.  What blends is the fraction of the total that stays
    in the own cell, :math:`f_i = A_i\,\mathrm{own}_i / \mathrm{total}_i` (A_i: the area of the vertex
    nearest x_i):

    .. math:: \mathrm{total}_v = \sum_j w_{vj}\,\mathrm{total}_j, \qquad
              \mathrm{own}_v = \frac{\mathrm{total}_v}{A_v} \sum_j w_{vj}\, f_j

    (how much each choice errs against a converged reference: docs/objects.md, "The near field").
    """
    if not model.measured or not {"own", "total"} <= set(model.measured):
        return None, None
    w, idx = weights
    own_i, total_i = model.measured["own"], model.measured["total"]  # (P, 3): mm⁻², 1
    A_i = area[cKDTree(vertices).query(model.x_i)[1]]  # the incident points' own cells, mm²
    f_i = np.divide(A_i[:, None] * own_i, total_i, out=np.zeros_like(own_i), where=total_i > 0)
    total = np.einsum("vk,vkc->vc", w, total_i[idx])
    own = np.einsum("vk,vkc->vc", w, np.clip(f_i, 0.0, 1.0)[idx]) * total / area[:, None]
    return own, total


@dataclass(kw_only=True)
class Transport:
    r"""The prepared transport: L_λ = T_λ E per channel (:func:`transport_matrices`).

    Either three matrices (one fall-off per channel) or one matrix T with the
    incident vertices' colour scale, :math:`T_\lambda = T\,\mathrm{diag}(s_\lambda)`; with a
    measured near field the own-area term is kept apart per channel:
    :math:`L_\lambda \mathrel{+}= \mathrm{own}_\lambda E`; the pairs beyond the near radius are the
    far field, :math:`L_\lambda \mathrel{+}= \alpha \odot W F_\lambda B_\lambda (s_\lambda E)`
    (:class:`translucency.render._far_field.FarField`).
    """

    matrices: list  # CSR (V × V), float32: one or three
    scale: np.ndarray | None = None  # (V, 3) colour scale of the incident vertex (one matrix)
    own: np.ndarray | None = None  # (V, 3) A_i own_i / π: each vertex's own area, per channel (measured)
    far: FarField | None = None  # the pairs beyond the near radius (None: truncated, or none there)
    reflectance: np.ndarray | None = None  # (V, 3) measured normal-incidence total reflectance, blended
    through: bool = False  # the model's through-body table is in the matrices (model/through.py)
    receivers: np.ndarray | None = None  # the vertices whose radiance it gives (None: all; :meth:`rows`)

    def incidence(self, name: str = "half-space", eta: float = 1.0):
        """The incidence law ``name`` for this object (:func:`translucency.model.incidence.incidence_law`)."""
        return incidence_law(name, self.reflectance, eta)

    @property
    def nnz(self) -> int:
        """Stored pairs per channel."""
        return int(self.matrices[0].nnz)

    def coarse(self, vertices, receivers) -> Transport:
        r"""A draft between a few vertices: the irradiance is given at ``receivers`` only (indices into the
        mesh's ``vertices``, mm), each standing for the vertices nearest it (its cell); the radiance
        comes back at the receivers.  The columns of every cell are summed once,
        :math:`T'_{rj} = \sum_{i \in j} T_{ri}`, and a shared colour scale is taken per cell (its
        mean) — a coarser quadrature of the same transport, for a light that moves (the full one when
        it stops)."""
        r = np.asarray(receivers, dtype=np.int64)
        v = np.asarray(vertices, dtype=np.float64)
        _, cell = cKDTree(v[r]).query(v)
        P = sp.csr_matrix((np.ones(len(v), np.float32), (np.arange(len(v)), cell)), shape=(len(v), len(r)))
        scale = None
        if self.scale is not None:
            count = np.bincount(cell, minlength=len(r))[:, None]
            scale = (P.T @ self.scale.astype(np.float64) / np.maximum(count, 1)).astype(np.float32)
        sub = self.rows(r)  # the receivers' rows, then their columns summed per cell
        far = sub.far
        if far is not None:
            far = dataclasses.replace(far, B=[(B @ P).tocsr() for B in far.B])
        matrices = [(T @ P).tocsr() for T in sub.matrices]
        return dataclasses.replace(sub, matrices=matrices, scale=scale, far=far, receivers=None)

    def rows(self, receivers) -> Transport:
        """The same transport giving the radiance of ``receivers`` (vertex indices) only: the rows of the
        near matrices and of the far field's interpolation (a relight of a few vertices under a light
        that lights them all)."""
        r = np.asarray(receivers, dtype=np.int64)
        far = None
        if self.far is not None:
            far = dataclasses.replace(
                self.far, W=self.far.W[r], alpha=self.far.alpha[r], label=self.far.label[r]
            )
        return dataclasses.replace(
            self,
            matrices=[T[r] for T in self.matrices],
            own=None if self.own is None else self.own[r],
            reflectance=None if self.reflectance is None else self.reflectance[r],
            far=far,
            receivers=r,
        )


@njit(parallel=True, cache=True)
def _csr_times_rgb(indptr, indices, data, X, out):
    """out = T X for a CSR matrix T and three columns X (V, 3): each row's pairs read once, rows on all
    cores."""
    for o in prange(indptr.shape[0] - 1):
        a0 = a1 = a2 = np.float32(0.0)
        for j in range(indptr[o], indptr[o + 1]):
            w, col = data[j], indices[j]
            a0 += w * X[col, 0]
            a1 += w * X[col, 1]
            a2 += w * X[col, 2]
        out[o, 0], out[o, 1], out[o, 2] = a0, a1, a2


def relight_vertices(transport: Transport, E: np.ndarray) -> np.ndarray:
    """Radiance per vertex (V, 3) for irradiance E (V,) or (V, 3): one sparse product, plus the far field
    (per receiving vertex, (R, 3), for a transport restricted by :meth:`Transport.rows`).

    With one shared matrix the three channels go through it together (the matrix is read once,
    rows on all cores, Numba); otherwise one SciPy product per channel.  The far field (if prepared)
    adds two sparse products and one K × K product per channel.
    """
    E = np.asarray(E, dtype=np.float32)
    E = np.repeat(E[:, None], 3, axis=1) if E.ndim == 1 else E
    rows = transport.matrices[0].shape[0]
    if transport.scale is None:  # one matrix per channel
        X = E
        out = np.stack([T @ E[:, ch] for ch, T in enumerate(transport.matrices)], axis=1)
    else:
        X, T, out = (
            np.ascontiguousarray(E * transport.scale),
            transport.matrices[0],
            np.empty((rows, 3), np.float32),
        )
        _csr_times_rgb(T.indptr, T.indices, T.data, X, out)
    if transport.own is not None:  # the receivers' own area: their own irradiance
        out += transport.own * (E if transport.receivers is None else E[transport.receivers])
    if transport.far is not None:  # the pairs beyond the near radius, through the clusters
        out += transport.far.apply(X)
    return out


def relight_object(
    transport: Transport, mesh, scene, light, viewpoint, *, eta: float = 1.0, incidence: str = "half-space"
):
    r"""What the camera at ``viewpoint`` sees of every vertex under ``light``: radiance (V, 3), W/(mm² sr).

    The whole chain once: the irradiance with shadows and the incidence law
    (:func:`vertex_irradiance`, :mod:`translucency.model.incidence`), the transport
    (:func:`relight_vertices`), the exit toward the camera — the boundary's Fresnel law
    (:func:`exit_fresnel`, η ≠ 1) or the incidence law's reciprocal exit (η = 1).

    Returns
    -------
    L : ndarray, shape (V, 3)
    E : ndarray, shape (V,) or (V, 3)
        The (effective) irradiance.
    law : the incidence law used (its ``name`` goes into summaries).

    Examples
    --------
    >>> L, E, law = relight_object(T, mesh, scene, light, camera.origin)  # doctest: +SKIP
    """
    law = transport.incidence(incidence, eta)
    E = vertex_irradiance(mesh, scene, light, eta, law)
    L = relight_vertices(transport, E) * exit_fresnel(mesh, viewpoint, eta)[:, None]
    exit_law = law.exit(view_cosines(mesh, viewpoint))
    return (L if exit_law is None else L * exit_law), E, law
