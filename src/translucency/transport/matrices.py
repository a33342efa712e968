r"""Transport assembly: the sparse near matrices and the far field of a fitted object, built once per
object so that a new light costs one sparse product per channel (:mod:`.relight`).

For incident vertex i (area :math:`A_i`, mm², irradiance :math:`E_i`, W/mm²) the light leaving vertex o is

.. math:: L(x_o) = \frac{1}{\pi} \sum_i A_i\, E_i\, R_d(x_i, x_o)
                 = \bigl(T E\bigr)_o, \qquad
          T_{oi} = \frac{A_i}{\pi}\, \alpha(x_o) \sum_k c_k(x_i)\, e^{d_k(x_i) |x_o - x_i|},

per channel (radiance in W/(mm² sr) per W/mm² of irradiance, so :math:`T` in sr⁻¹; the exitance
:math:`\pi L` is what the virtual acquisition tallies, so the exit is taken as Lambertian), with the
parameters :math:`c_k, d_k` of every vertex from :mod:`.parameters`.  :math:`T` holds the pairs closer
than a near radius R (mm), found with a k-d tree — no O(V²) loop — and the pairs beyond it go through a
hierarchical far field (clustered sources, a K × K operator, interpolation back to the vertices:
:mod:`translucency.transport._far_field`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .._validate import TranslucencyError
from ..geometry import vertex_areas
from ..model.lean import has_lean
from ..model.through import through_factor
from ._far_field import far_field_operator
from .parameters import measured_per_vertex, neighbour_weights, vertex_parameters
from .relight import Transport

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
    >>> import translucency as tl
    >>> from translucency.render import object_of_model
    >>> model = tl.load_model(tl.data.example_path("spot_coarse.model.zip"))   # the example object
    >>> mesh, _ = object_of_model(model, {})
    >>> from translucency.transport.matrices import default_radius
    >>> r = default_radius(model, mesh)
    >>> bool(0 < r <= model.energy_radius(0.99).max())
    True
    """
    V = len(mesh.vertices)
    fit_pairs = np.sqrt(0.5 * max_pairs * mesh.area / (np.pi * V**2))
    return float(min(np.max(model.energy_radius(0.99)), fit_pairs))


def _near_pairs(model, mesh, v: np.ndarray, radius: float | None, max_pairs: float, shrink: bool | None):
    r"""The near radius (mm) and the vertex pairs within it (P, 2), at most ``max_pairs`` both ways with
    the diagonal.  A radius of the user's that gives more is refused; the default
    (:func:`default_radius`, which assumes the vertices evenly spread; ``shrink``: a radius passed in
    that was the default) shrinks until the pairs fit: they grow as r², so each try scales r by
    :math:`0.95 \sqrt{p_{max} / p}` (the far field takes what the near field no longer holds)."""
    V = len(v)
    tree = cKDTree(v)
    shrink = radius is None if shrink is None else shrink
    rad = default_radius(model, mesh, max_pairs=max_pairs) if radius is None else float(radius)
    for _ in range(8):
        pairs = tree.query_pairs(rad, output_type="ndarray")
        count = 2 * len(pairs) + V
        if count <= max_pairs:
            return rad, pairs
        if not shrink or V >= max_pairs:
            break
        rad *= 0.95 * np.sqrt(max(max_pairs - V, 1.0) / max(count - V, 1.0))
    given = not shrink
    raise TranslucencyError(
        f"radius: {rad:.3g} mm gives {count:,} vertex pairs (at most {max_pairs:,.0f}); "
        + ("lower --radius" if given else f"{V:,} vertices are too many for the near field's pairs")
    )


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
    through: bool | None = None,
    shrink: bool | None = None,
):
    r"""The sparse transport T of the module docstring, as a :class:`Transport` (one matrix per
    channel, or one matrix and the colour scale for the shared-colour model).

    ``radius`` defaults to the model's 99 % energy radius (largest over points and channels); a default
    radius shrinks where its pairs exceed ``max_pairs``, a given one is refused there (``shrink=True``:
    the given radius is the default, chosen beforehand — :class:`~translucency.transport.PreparedObject`).
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
    three matrices even for a shared-colour model.  ``through=None`` (the default) uses the table wherever
    the model holds one — every fit on a mesh stores it, and with the unscattered light kept out of the data
    it wins or ties every case of docs/through-body.md's table; ``through=False``, or a model without the
    table, is the paper's model.

    **Far field.**  The pairs beyond ``radius`` are not dropped: ``far_field`` (default) adds them
    hierarchically (:mod:`translucency.transport._far_field`: ``clusters`` source clusters, K², default
    about 4 · surface / (π radius²), 256 to 3,000, with members opened near the radius; the smooth
    result interpolated back to the vertices), so light that enters one side of a thick body leaves
    the other.  With a measured near field the column normalisation above applies to near and far
    together — each vertex's kernel still carries exactly its measured total; without it the far field
    adds the profile's tail.  ``far_field=False`` truncates at ``radius`` (the ablation).  Memory: the
    near pairs plus K² float32 per matrix (36 MB at K = 3,000) and (k + 1) · V entries.

    Examples
    --------
    >>> import numpy as np
    >>> import translucency as tl
    >>> from translucency.render import object_of_model
    >>> model = tl.load_model(tl.data.example_path("spot_coarse.model.zip"))   # the example object
    >>> mesh, _ = object_of_model(model, {})
    >>> from translucency.transport.matrices import transport_matrices
    >>> from translucency.transport.relight import relight_vertices
    >>> T = transport_matrices(model, mesh)
    >>> E = np.ones(len(mesh.vertices))   # a uniform irradiance, W/mm²
    >>> L = relight_vertices(T, E)
    >>> L.shape, bool((L > 0).all())
    ((402, 3), True)
    """
    v = np.asarray(mesh.vertices, dtype=np.float64)
    V = len(v)
    area = vertex_areas(mesh)  # mm²
    weights = neighbour_weights(model, mesh)
    c, d, s = vertex_parameters(model, mesh, weights=weights)
    own, total = measured_per_vertex(model, weights, v, area)
    rad, pairs = _near_pairs(model, mesh, v, radius, max_pairs, shrink)
    # both directions of every pair; each vertex with itself below
    i = np.concatenate([pairs[:, 0], pairs[:, 1]])
    o = np.concatenate([pairs[:, 1], pairs[:, 0]])
    r = np.linalg.norm(v[o] - v[i], axis=1)
    if r_min is None:
        e = np.asarray(mesh.edges_unique_length)
        r_min = 0.5 * float(e.mean())
    r = np.maximum(r, r_min)
    alpha = model.alpha.values if len(model.alpha.values) == V else model.alpha.at(v)
    table, lean = _blended_tables(model, weights, through)
    # shared colour (one fall-off, C = 1): T_λ = T · diag(s_λ) — one matrix, the scale goes with E
    # (not with the through table: it is per channel)
    shared = c.shape[1] == 1 and table is None
    normals = np.asarray(mesh.vertex_normals, dtype=np.float64)
    cos_io = np.einsum("mk,mk->m", normals[i], normals[o]) if table is not None else None
    # the pairs beyond rad: clusters and their K × K operator, b_i = A_i/π until normalised below
    far = (
        far_field_operator(
            model, v=v, area=area, alpha=alpha, weights=weights, c=c, d=d, radius=rad,
            surface=float(mesh.area), clusters=clusters, through=None if table is None else (table, normals),
        )
        if far_field
        else None
    )  # fmt: skip
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
            vals = _balanced(vals, (i, o), area, tau, far, ch, shared, balance_rows)
            diag = None  # the own area rides beside the matrix (Transport.own), per channel
        mats.append(_csr(vals, diag, i, o, V))
    if own is None:
        return Transport(
            matrices=mats, scale=s.astype(np.float32) if shared else None, far=far, lean=lean, radius=rad
        )
    scale = tau if shared else None
    return Transport(
        matrices=mats,
        scale=None if scale is None else scale.astype(np.float32),
        own=(area[:, None] / np.pi * own).astype(np.float32),
        far=far,
        reflectance=total,
        through=table is not None,
        lean=lean,
        radius=rad,
    )


def _blended_tables(model, weights, through: bool | None):
    """(the through-body table blended to every vertex (V, 4, 8, 3), or None: the paper's model; the lean's
    κ and λ blended to every vertex (V, 2, 3), or None) — each vertex's from its incident points' with the
    profile weights (:mod:`translucency.model.through`, :mod:`translucency.model.lean`)."""
    table = None
    if through is not False and model.measured and "through" in model.measured:
        w_b, idx_b = weights
        table = np.einsum("vk,vkabc->vabc", w_b, model.measured["through"][idx_b])
    lean = None
    if has_lean(model):  # (transport/lean.py applies it)
        w_b, idx_b = weights
        lean = np.einsum("vk,vkac->vac", w_b, model.measured["lean"][idx_b]).astype(np.float32)
    return table, lean


def _balanced(vals, pairs, area, tau, far, ch: int, shared: bool, balance_rows: bool):
    r"""The near values of channel ``ch`` scaled so that every column carries its measured spread (and,
    with ``balance_rows``, every row gathers it: :func:`transport_matrices`' "Rows"), the far field's
    columns normalised alike.

    The spread of column i is normalised to carry 1 (shared colour: the scale carries each channel's
    :math:`\tau_i = \mathrm{total}_i - A_i\,\mathrm{own}_i`) or :math:`\tau_i` itself (one matrix per
    channel); :math:`T_{oi} = x_o K_{oi} y_i` by alternating column and row steps (Sinkhorn).
    """
    i, o = pairs
    V = len(area)
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
    if far is not None:
        far.normalise(ch, factor)
    return vals * x[o] * factor[i]


def _csr(vals, diag, i, o, V: int):
    """The (V × V) float32 CSR matrix of the pair values ``vals`` at (receiver o, source i), with ``diag`` on
    the diagonal (None: the own area rides beside it)."""
    if diag is None:
        return sp.csr_matrix((vals.astype(np.float32), (o, i)), shape=(V, V))
    rows, cols = np.concatenate([o, np.arange(V)]), np.concatenate([i, np.arange(V)])
    return sp.csr_matrix((np.concatenate([vals, diag]).astype(np.float32), (rows, cols)), shape=(V, V))
