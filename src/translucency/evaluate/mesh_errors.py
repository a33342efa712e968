r"""Errors of a per-vertex model against a mesh data set: the planar errors (:mod:`.errors`) on an object.

A mesh data set holds :math:`R_d(\vec x_i, v)` per incident vertex :math:`\vec x_i` and every vertex v
(:mod:`translucency.acquire.mesh`), read as the fit reads it (:func:`translucency.fit.mesh.read_pairs`):
r = |v − x_i| Euclidean, and a pair counts when it is finite and r is at least the fit's exclusion radius
(half the mean edge length: the incident vertex's own tally, the direct spot, is left out).  The model's
:math:`\hat R_d(\vec x_i, v) = \alpha(v)\, P_i(r)` is evaluated at the same pairs, α included, times the
point's through-body table :math:`k_i(n_i \cdot n_v, r)` (:mod:`translucency.model.through`) where the model
holds one, as ``render`` draws it by default (``through=False``: the paper's model alone).  Over the
pairs, RGB summed,

.. math:: \mathrm{rel\_l2} = \frac{\lVert \hat R_d - R_d \rVert_2}{\lVert R_d \rVert_2},

overall, per distance band of r (near < 1 mm, mid 1–4 mm, far > 4 mm, :data:`.errors.BANDS`), per
incident point, per outgoing vertex (over the pairs with r < ``map_radius``) and per distance ring
(:data:`DISTANCE_EDGES`, for the error-against-distance figure).  ``energy[b]`` is the relative L2 error
over the points of the energy :math:`E_{ib} = \sum_{v \in b} A_v R_d(\vec x_i, v)` of each band, and of
all pairs (``"surface"``).

**Noise.**  A photon leaving through a triangle adds its barycentric weights :math:`\phi_v` to the
triangle's three vertices, so the tally of vertex v over N photons has variance :math:`N\,E[\phi_v^2]`
(to first order), not the Poisson :math:`N\,E[\phi_v]`: for exits spread evenly over the vertex's
triangles :math:`E[\phi^2]/E[\phi] = (A/6)/(A/3) = 1/2`, and

.. math:: \sigma^2(\vec x_i, v) = \frac{R_d(\vec x_i, v)}{2\, N A_v}\quad[\mathrm{mm}^{-4}],

an unbiased estimate from the data set's own value.  Two acquisitions of the demo's pig with other
seeds differ by 0.44 / 0.49 / 0.50 times the Poisson variance in the near / mid / far bands; the
factor is checked in ``tests/test_evaluate_mesh.py``.  ``noise`` is
:math:`\sqrt{\sum \sigma^2}/\lVert R_d \rVert` per band: what a perfect model would score.

Against an independent acquisition of the same object and incident vertices (another seed: ``translucency
evaluate --truth``) the truth's noise is independent of the model, and ``beyond_noise`` =
:math:`\sqrt{\max(\lVert \hat R_d - R_d\rVert^2 - \sum\sigma^2, 0)}/\lVert R_d\rVert` estimates the error
against the noise-free material (in-sample this subtraction is not valid: the fit followed that noise).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError
from ..acquire.mesh import TALLY_VARIANCE_FACTOR  # the tally's variance over its Poisson value
from ..fit.mesh import exclusion_radius, mean_edge_length, read_pairs
from ..io.mesh_dataset import MeshDataset, open_mesh_dataset
from ..io.vertex_model import check_vertex_model
from ..model.through import through_factor
from .errors import BANDS, PlanarErrors, beyond

#: ring edges (mm) of the error-against-distance curve; 1 and 4 mm are the bands' edges
DISTANCE_EDGES = np.array(
    [0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0, 48.0, 64.0, 128.0]
)


@dataclass
class MeshErrors:
    """Error statistics of one per-vertex model on one mesh data set (the reference)."""

    rel_l2: float
    bands: dict  # band -> rel_l2
    noise: dict  # "all" and band -> the reference's noise floor
    beyond_noise: dict  # "all" and band -> error beyond the reference's noise (meaningful held out only)
    energy: dict  # band and "surface" -> relative error of the per-point energies
    energy_noise: dict  # band and "surface" -> noise of those energies
    per_point: np.ndarray  # (P,) relative error per incident point (NaN where flagged)
    per_point_noise: np.ndarray  # (P,) the reference's noise per incident point
    per_point_beyond: np.ndarray  # (P,) error beyond the noise per incident point
    per_vertex: np.ndarray  # (V,) relative error per outgoing vertex over the pairs with r < map_radius
    per_vertex_noise: np.ndarray  # (V,) the reference's noise there
    distance: dict  # "edges_mm" (R+1,), "rel_l2", "noise", "pairs" (R,) per ring of r
    map_radius: float
    exclusion_mm: float
    through: bool = False  # whether the model's through-body table was in the prediction

    def summary(self) -> dict:
        """The JSON fields of ``translucency evaluate`` on a mesh data set (NaN for an empty band: the
        files pass through :func:`.errors.finite_or_null`)."""
        out = PlanarErrors.summary(self)  # the planar errors' fields: the same names, the same meaning
        out["per_point"]["values"] = self.per_point.tolist()
        out["exclusion_mm"] = self.exclusion_mm
        out["through"] = self.through
        out["by_distance"] = {k: np.asarray(v).tolist() for k, v in self.distance.items()}
        out["by_distance"]["pairs"] = [int(n) for n in self.distance["pairs"]]  # counts
        return out


def check_same_points(data: MeshDataset, truth: MeshDataset) -> None:
    """Refuse, in one line naming the first difference, a truth of another mesh or other incident vertices.

    ``acquire mesh`` picks its incident vertices by farthest-point sampling of the mesh alone (not of the
    seed), so the same mesh and ``--points`` give the same ones; a truth with other points is not
    evaluated (its pairs would not be the model's).
    """
    v_d, v_t = data["vertices"], truth["vertices"]
    if v_d.shape != v_t.shape:
        raise TranslucencyError(
            f"{truth.path}: a mesh of {len(v_t):,} vertices, the data set's has {len(v_d):,}; "
            "the truth must be an acquisition of the same mesh"
        )
    moved = np.flatnonzero(np.abs(v_d - v_t).max(axis=1) > 1e-4)
    if moved.size:
        raise TranslucencyError(
            f"{truth.path}: vertex {moved[0]} lies elsewhere than in {data.path}; "
            "the truth must be an acquisition of the same mesh"
        )
    inc_d, inc_t = data["incident"], truth["incident"]
    n = min(len(inc_d), len(inc_t))
    differ = np.flatnonzero(inc_d[:n] != inc_t[:n])
    if differ.size:
        i = int(differ[0])
        raise TranslucencyError(
            f"{truth.path}: incident point {i} is vertex {inc_t[i]}, the data set's is vertex {inc_d[i]}; "
            "the truth must have the same incident vertices (the same mesh and --points, another --seed)"
        )
    if len(inc_d) != len(inc_t):
        raise TranslucencyError(
            f"{truth.path}: {len(inc_t)} incident points, the data set {len(inc_d)} (the first {n} agree); "
            "the truth must have the same incident vertices (the same mesh and --points, another --seed)"
        )


def check_model_points(model, ds: MeshDataset) -> None:
    """Refuse, in one line, a model that is not per-vertex, an unfinished data set, or a model whose
    incident points are not the data set's incident vertices (naming the first that differs)."""
    check_vertex_model(model, f"evaluating on the mesh data set {ds.path}")
    if not ds.complete():
        raise TranslucencyError(f"{ds.path}: the acquisition is unfinished; resume it before evaluating")
    incident = ds["incident"]
    x_i = ds["vertices"].astype(np.float64)[incident]
    if model.n_points != ds.n_points:
        raise TranslucencyError(
            f"{ds.path}: the model has {model.n_points} incident points, the data set {ds.n_points}; "
            "evaluate a model on an acquisition of its own incident points"
        )
    off = np.flatnonzero(np.abs(model.x_i - x_i).max(axis=1) > 1e-4)
    if off.size:
        i = int(off[0])
        raise TranslucencyError(
            f"{ds.path}: the model's incident point {i} at {_mm(model.x_i[i])} is not the data set's "
            f"(vertex {incident[i]} at {_mm(x_i[i])}); evaluate a model on an acquisition of its own points"
        )


def mesh_errors(
    model,
    dataset,
    *,
    exclusion_mm: float | None = None,
    flagged=None,
    map_radius: float = 4.0,
    chunk_points: int = 16,
    through: bool | None = None,
) -> MeshErrors:
    """Relative L2 errors of a per-vertex ``model`` on a mesh data set: overall, per band, point and vertex.

    Parameters
    ----------
    model : ReflectanceModel
        A mesh model whose incident points are the data set's incident vertices (its fit, or the fit of
        another acquisition of the same mesh and points).
    dataset : MeshDataset or path
        The reference: the data set it was fitted to (in-sample) or an independent acquisition.
    exclusion_mm : float, optional
        Pairs closer than this are left out; default the fit's default, half the mean edge length.
    flagged : array of bool, optional
        Incident points to leave out.
    map_radius : float
        The per-vertex errors sum the pairs with r below this (mm).
    through : bool, optional
        The model's through-body table in the prediction: default, wherever the model holds one (what
        ``render`` draws); False: the paper's model.

    Returns
    -------
    MeshErrors

    Examples
    --------
    A ball of marble scanned, fitted, and its model's errors on the data (per band; ``near`` is empty:
    the ball's vertices lie farther apart than 1 mm):

    >>> import tempfile, trimesh
    >>> import translucency as tl
    >>> from translucency.evaluate.mesh_errors import mesh_errors
    >>> ball = trimesh.creation.icosphere(2, radius=4.0)
    >>> data = tl.acquire_mesh(ball, tempfile.mkdtemp() + "/ball.zarr", "homogeneous:marble", voxel_mm=1.0,
    ...                        points=4, photons=300, index_matched=True)
    >>> fitting = tl.fit_model(data, "iso", n_terms=1, max_rounds=1)
    >>> e = mesh_errors(fitting.model, data)
    >>> sorted(e.bands), bool(0 < e.rel_l2 < 1)
    (['far', 'mid', 'near'], True)
    """
    ds = dataset if isinstance(dataset, MeshDataset) else open_mesh_dataset(dataset)
    check_model_points(model, ds)
    vertices = ds["vertices"].astype(np.float64)
    x_i = vertices[ds["incident"]]
    P, V = ds.n_points, len(vertices)
    area = ds["vertex_area"].astype(np.float64)
    exclusion = exclusion_radius(mean_edge_length(vertices, np.asarray(ds["faces"])), exclusion_mm)
    flagged = np.zeros(P, bool) if flagged is None else np.asarray(flagged, bool)
    alpha_o = model.alpha.at(vertices)  # α per vertex (V,): the model's texture at the data set's vertices
    # the through-body table per point (P, 4, 8, 3), read at each pair's (n_i · n_v, r); None: the paper's
    table = model.measured.get("through") if through is not False and model.measured else None
    normals = np.asarray(ds["normals"], dtype=np.float64) if table is not None else None
    # σ² per pair = R_d · (factor / (N A_v)), mm⁻⁴ (module docstring)
    var_scale = TALLY_VARIANCE_FACTOR / (float(ds.header["photons"]) * np.maximum(area, 1e-12))
    sums = _empty_sums(P, V)
    for s in range(0, P, chunk_points):
        e = min(s + chunk_points, P)
        y, r, ok = read_pairs(ds.group, vertices, x_i, exclusion, s, e)
        y = y.astype(np.float64)
        ok = ok & ~flagged[s:e, None]
        pred = _predict_pairs(model, ds, vertices, alpha_o, table, normals, s, e, r)
        terms = _pair_terms(pred, y, ok, var_scale, area)
        _add_chunk(sums, s, e, r, ok, terms, map_radius)
    return _mesh_result(sums, flagged, map_radius, exclusion, table is not None)


def _empty_sums(P: int, V: int) -> dict:
    """Zeroed accumulators: per band, per point, per band's point energies, per vertex and per ring."""
    n_rings = len(DISTANCE_EDGES) - 1
    names = (*BANDS, "surface")
    sums = {key: {b: 0.0 for b in BANDS} for key in ("err2", "ref2", "var")}
    sums.update({key: {b: np.zeros(P) for b in names} for key in ("e_model", "e_data", "e_var")})
    sums.update({key: np.zeros(P) for key in ("pt_err2", "pt_ref2", "pt_var")})
    sums.update({key: np.zeros(V) for key in ("vx_err", "vx_ref", "vx_var")})
    sums.update({key: np.zeros(n_rings) for key in ("ring_err", "ring_ref", "ring_var", "ring_n")})
    return sums


def _predict_pairs(model, ds, vertices, alpha_o, table, normals, s: int, e: int, r) -> np.ndarray:
    """The model's R_d (k, V, 3) of points [s, e) at every vertex, times k_i(n_i · n_v, r) with a table."""
    V = len(vertices)
    i = np.broadcast_to(np.arange(s, e)[:, None], r.shape)
    pred = model.R_d(i, np.broadcast_to(vertices, (e - s, V, 3)), alpha_o=np.broadcast_to(alpha_o, r.shape))
    if table is not None:  # k_i(n_i · n_v, r) per channel, dimensionless
        cos = normals[ds["incident"][s:e]] @ normals.T
        for c in range(3):
            k = through_factor(table[..., c], i.ravel(), cos.ravel(), r.ravel())
            pred[..., c] *= k.reshape(r.shape)
    return pred


def _pair_terms(pred, y, ok, var_scale, area) -> tuple:
    """Per pair (RGB summed, 0 where the pair does not count): error², reference², variance (mm⁻⁴) and
    the energies A_v R_d of model, reference and their variance."""
    d2 = np.where(ok, ((pred - y) ** 2).sum(2), 0.0)  # (k, V), mm⁻⁴
    y2 = np.where(ok, (y**2).sum(2), 0.0)
    v2 = np.where(ok, (y * var_scale[None, :, None]).sum(2), 0.0)
    p_e = np.where(ok, pred.sum(2), 0.0) * area  # energy per pair (RGB summed), per unit power
    y_e = np.where(ok, y.sum(2), 0.0) * area
    v_e = v2 * area**2
    return d2, y2, v2, p_e, y_e, v_e


def _add_chunk(sums: dict, s: int, e: int, r, ok, terms: tuple, map_radius: float) -> None:
    """Add the pairs of points [s, e) to the accumulators: per band, point, ring and near vertex."""
    d2, y2, v2, p_e, y_e, v_e = terms
    energies = ((sums["e_model"], p_e), (sums["e_data"], y_e), (sums["e_var"], v_e))
    for b, (lo, hi) in BANDS.items():
        sel = (r >= lo) & (r < hi)
        sums["err2"][b] += float(d2[sel].sum())
        sums["ref2"][b] += float(y2[sel].sum())
        sums["var"][b] += float(v2[sel].sum())
        for acc, x in energies:
            acc[b][s:e] = np.where(sel, x, 0.0).sum(1)
    for acc, x in energies:
        acc["surface"][s:e] = x.sum(1)
    sums["pt_err2"][s:e], sums["pt_ref2"][s:e], sums["pt_var"][s:e] = d2.sum(1), y2.sum(1), v2.sum(1)
    edges = DISTANCE_EDGES
    ring = np.clip(np.searchsorted(edges, r, side="right") - 1, 0, len(edges) - 2)
    for key, x in (("ring_err", d2), ("ring_ref", y2), ("ring_var", v2), ("ring_n", ok.astype(float))):
        sums[key] += np.bincount(ring[ok], x[ok], minlength=len(edges) - 1)
    near = r < map_radius
    sums["vx_err"] += np.where(near, d2, 0.0).sum(0)
    sums["vx_ref"] += np.where(near, y2, 0.0).sum(0)
    sums["vx_var"] += np.where(near, v2, 0.0).sum(0)


def _ratio(a, b) -> float:
    """sqrt(a / b), NaN where b is not positive."""
    return float(np.sqrt(a / b)) if b > 0 else float("nan")


def _ratios(a, b) -> np.ndarray:
    """Element-wise sqrt(a / b), NaN where b is not positive."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(b > 0, np.sqrt(a / np.where(b > 0, b, 1.0)), np.nan)


def _mesh_result(sums: dict, flagged, map_radius: float, exclusion: float, through: bool) -> MeshErrors:
    """The relative errors of the summed squares, with the flagged points left out of the per-point ones."""
    err2, ref2, var = sums["err2"], sums["ref2"], sums["var"]
    e_model, e_data, e_var = sums["e_model"], sums["e_data"], sums["e_var"]
    pt_err2, pt_ref2, pt_var = sums["pt_err2"], sums["pt_ref2"], sums["pt_var"]
    keep = ~flagged
    tot_e, tot_r, tot_v = sum(err2.values()), sum(ref2.values()), sum(var.values())
    return MeshErrors(
        rel_l2=_ratio(tot_e, tot_r),
        bands={b: _ratio(err2[b], ref2[b]) for b in BANDS},
        noise={"all": _ratio(tot_v, tot_r), **{b: _ratio(var[b], ref2[b]) for b in BANDS}},
        beyond_noise={
            "all": beyond(tot_e, tot_v, tot_r),
            **{b: beyond(err2[b], var[b], ref2[b]) for b in BANDS},
        },
        energy={
            b: _ratio(float(((e_model[b] - e_data[b])[keep] ** 2).sum()), float((e_data[b][keep] ** 2).sum()))
            for b in e_model
        },
        energy_noise={
            b: _ratio(float(e_var[b][keep].sum()), float((e_data[b][keep] ** 2).sum())) for b in e_model
        },
        per_point=np.where(keep, _ratios(pt_err2, pt_ref2), np.nan),
        per_point_noise=np.where(keep, _ratios(pt_var, pt_ref2), np.nan),
        per_point_beyond=np.where(keep, beyond(pt_err2, pt_var, pt_ref2), np.nan),
        per_vertex=_ratios(sums["vx_err"], sums["vx_ref"]),
        per_vertex_noise=_ratios(sums["vx_var"], sums["vx_ref"]),
        distance={
            "edges_mm": DISTANCE_EDGES,
            "rel_l2": _ratios(sums["ring_err"], sums["ring_ref"]),
            "noise": _ratios(sums["ring_var"], sums["ring_ref"]),
            "pairs": sums["ring_n"],
        },
        map_radius=float(map_radius),
        exclusion_mm=exclusion,
        through=through,
    )


def _mm(x) -> str:
    """A position as '(x, y, z) mm' with plain numbers."""
    return "(" + ", ".join(f"{float(v):.3g}" for v in x) + ") mm"
