r"""Errors of a fitted model against a planar data set.

Over the valid pairs :math:`(\vec x_i, \vec x_o)` of the data set (mask set,
finite, r at least the exclusion radius), summed over the three channels:

.. math:: \mathrm{rel\_l2} = \frac{\lVert \hat R_d - R_d \rVert_2}{\lVert R_d \rVert_2},

and the same restricted to the distance bands near (r < 1 mm), mid
(1–4 mm) and far (> 4 mm).  ``noise`` is the part of it that the
measurement noise alone explains, :math:`\sqrt{\sum \sigma^2}/\lVert R_d\rVert`
in each band — a perfect model would score about that.

**Energy-weighted errors** — what a renderer sees: per incident point the
energy of each band, :math:`E_{ib} = \sum_{o \in b} R_d(\vec x_i, \vec x_o)\, p^2`
(p the pixel pitch), and of the whole window; ``energy[b]`` is
:math:`\lVert \hat E_{\cdot b} - E_{\cdot b}\rVert / \lVert E_{\cdot b}\rVert` over the points,
and ``energy["total"]`` the same for the total diffuse reflectance per point
(the model's :math:`\int R_d\,dA` against the data set's ``total_diffuse``,
which counts light leaving outside the window too).

Evaluated against an independent acquisition of the same incident points
(``translucency evaluate --truth``), these measure the model against the
material rather than against the noise it was fitted to.  The truth's own
noise is then independent of the model, so the squared error splits into
the model's error and the truth's variance, and

.. math:: \mathrm{beyond\_noise} = \sqrt{\max(\lVert \hat R_d - R_d \rVert^2 - \sum \sigma^2, 0)}
          / \lVert R_d \rVert

estimates the model's error against the noise-free material (0 when the
error is within the noise).  In-sample (the fitted data as the reference)
this subtraction is not valid: the fit has followed part of that noise.
``energy_noise`` is the noise of the energies the same way (the truth's
variance summed over the band's pixels).

Maps: the error per incident point, :math:`\lVert \hat R_{d,i} - R_{d,i}\rVert / \lVert R_{d,i}\rVert`
over its window, and per outgoing pixel of the sample, the same over the pairs
that end in that pixel with r < ``map_radius`` (4 mm: beyond, photon noise
dominates every model's error) — the paper's Figure 1, right.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError
from ..cluster import compact, expand, in_order_window, open_cluster
from ..geometry import SampleGrid, window_geometry
from ..io.dataset import PlanarDataset, open_dataset

BANDS = {"near": (0.0, 1.0), "mid": (1.0, 4.0), "far": (4.0, np.inf)}


@dataclass
class PlanarErrors:
    """Error statistics of one model on one data set."""

    rel_l2: float
    bands: dict  # band -> rel_l2
    noise: dict  # "all" and band -> noise floor
    energy: dict  # band, "window" and "total" -> relative error of the per-point energies
    per_point: np.ndarray  # (P,) relative error per incident point (NaN where flagged/no data)
    per_pixel: np.ndarray  # (H, W) relative error per outgoing pixel on the sample grid
    grid: SampleGrid
    map_radius: float
    beyond_noise: dict | None = None  # "all" and band -> error beyond the reference's noise
    energy_noise: dict | None = None  # band and "window" -> noise of the per-point energies
    per_point_noise: np.ndarray | None = None  # (P,) the reference's noise per incident point
    per_pixel_noise: np.ndarray | None = None  # (H, W) the reference's noise per outgoing pixel
    per_point_beyond: np.ndarray | None = None  # (P,) error beyond the noise per incident point
    per_pixel_beyond: np.ndarray | None = None  # (H, W) error beyond the noise per outgoing pixel

    def summary(self) -> dict:
        """The JSON fields of ``translucency evaluate`` (NaN for an empty band: files written from it pass
        through :func:`finite_or_null`, which makes it null)."""
        out = {"rel_l2": self.rel_l2}
        out.update({f"rel_l2_{b}": v for b, v in self.bands.items()})
        out["noise_floor"] = self.noise
        out["beyond_noise"] = self.beyond_noise
        out["energy_error"] = self.energy
        out["energy_noise"] = self.energy_noise
        pp = self.per_point[np.isfinite(self.per_point)]
        out["per_point"] = {
            "median": float(np.median(pp)) if pp.size else None,
            "p95": float(np.quantile(pp, 0.95)) if pp.size else None,
        }
        return out


def finite_or_null(value):
    """``value`` with every non-finite float (NaN, inf) replaced by None, through dicts and lists."""
    if isinstance(value, dict):
        return {k: finite_or_null(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_or_null(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if np.isfinite(value) else None
    return value


def beyond(err2, var, ref2):
    """The relative error left after the reference's noise: sqrt(max(err² − var, 0) / ref²) (NaN if
    ref² = 0); element-wise on arrays."""
    err2, var, ref2 = (np.asarray(v, dtype=np.float64) for v in (err2, var, ref2))
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(ref2 > 0, np.sqrt(np.maximum(err2 - var, 0.0) / np.where(ref2 > 0, ref2, 1.0)), np.nan)
    return float(out) if out.ndim == 0 else out


def planar_errors(
    model,
    dataset,
    *,
    exclusion_mm: float | None = None,
    chunk_points: int = 256,
    flagged=None,
    map_radius: float = 4.0,
    scheduler=None,
) -> PlanarErrors:
    """Relative L2 errors of ``model`` on a planar data set, overall, per band and as maps.

    Parameters
    ----------
    model : ReflectanceModel
        A planar model whose incident points are those of the data set.
    dataset : PlanarDataset or path
    exclusion_mm : float, optional
        Pairs closer than this are left out; default one pixel (as the fit).
    flagged : array of bool, optional
        Incident points to leave out (points the fit flagged).
    scheduler : str or Cluster, optional
        Where the chunks are evaluated (:func:`translucency.cluster.open_cluster`): ``"threads"`` (this
        process, the default), ``"local:N"`` or ``"tcp://HOST:PORT"``; the errors are the same.

    Returns
    -------
    PlanarErrors
    """

    ds = dataset if isinstance(dataset, PlanarDataset) else open_dataset(dataset)
    x_i = ds["x_i"].astype(np.float64)
    if model.n_points != ds.n_points or not np.allclose(model.x_i[:, :2], x_i, atol=1e-4):
        raise TranslucencyError(
            f"{ds.path}: the model's {model.n_points} incident points are not the data set's "
            f"{ds.n_points}; evaluate a model on the data set it was fitted to"
        )
    exclusion = ds.pitch if exclusion_mm is None else float(exclusion_mm)
    origin = ds["window_origin"].astype(np.float64)
    grid = SampleGrid.covering(origin, ds.pitch, ds.window)
    flagged = np.zeros(ds.n_points, bool) if flagged is None else np.asarray(flagged, bool)
    ranges = [(s, min(s + chunk_points, ds.n_points)) for s in range(0, ds.n_points, chunk_points)]
    common = (x_i, origin, grid, exclusion, flagged, map_radius)
    sums = _sum_chunks(model, ds, ranges, common, scheduler, grid.shape[0] * grid.shape[1])
    energy, energy_noise = _energy_errors(model, ds, sums, ~flagged)
    return _planar_result(sums, energy, energy_noise, grid, map_radius)


def _ratio(a, b) -> float:
    """sqrt(a / b), NaN where b is not positive."""
    return float(np.sqrt(a / b)) if b > 0 else float("nan")


def _sum_chunks(model, ds, ranges, common, scheduler, n_px: int) -> dict:
    """Every chunk's :func:`_chunk_sums` added up in chunk order: per band, point, point energy and pixel."""
    P = ds.n_points
    sums = {key: {b: 0.0 for b in BANDS} for key in ("err2", "ref2", "var")}
    sums["per_point"] = np.full(P, np.nan)
    sums.update({key: np.zeros(P) for key in ("pt_err2", "pt_ref2", "pt_var")})
    # per point and band: the energy Σ R_d p² of model and data (RGB summed), for the energy-weighted errors
    sums.update({key: {b: np.zeros(P) for b in (*BANDS, "window")} for key in ("e_model", "e_data", "e_var")})
    sums.update({key: np.zeros(n_px) for key in ("pix_err", "pix_ref", "pix_var")})
    e_model, e_data, e_var = sums["e_model"], sums["e_data"], sums["e_var"]
    # every chunk's sums, added in chunk order (in this process, or as tasks that read their own chunks)
    for (s, e), chunk in zip(ranges, _chunk_sums_in_order(model, ds, ranges, common, scheduler)):
        for key in ("err2", "ref2", "var"):
            for b in BANDS:
                sums[key][b] += chunk[key][b]
        for b in e_model:
            e_model[b][s:e], e_data[b][s:e], e_var[b][s:e] = chunk["energy"][b]
        point_sums = (sums["pt_err2"], sums["pt_ref2"], sums["pt_var"], sums["per_point"])
        for acc, x in zip(point_sums, chunk["per_point"]):
            acc[s:e] = x
        for key in ("pix_err", "pix_ref", "pix_var"):
            sums[key] += expand(chunk[key], n_px)
    return sums


def _energy_errors(model, ds, sums: dict, keep) -> tuple[dict, dict]:
    """The relative errors of the per-point energies per band and window, of the total diffuse reflectance
    (the model's times its mean α against the data set's ``total_diffuse``), and the energies' noise."""
    e_model, e_data, e_var = sums["e_model"], sums["e_data"], sums["e_var"]
    energy = {
        b: _ratio(float(((e_model[b] - e_data[b])[keep] ** 2).sum()), float((e_data[b][keep] ** 2).sum()))
        for b in e_model
    }
    total_data = ds["total_diffuse"].astype(np.float64).sum(axis=1)  # (P,) RGB summed
    with np.errstate(invalid="ignore", over="ignore"):
        alpha_mean = float(np.mean(model.alpha.values))
        total_model = model.total_reflectance().sum(axis=1) * alpha_mean
    energy["total"] = _ratio(
        float(((total_model - total_data)[keep] ** 2).sum()), float((total_data[keep] ** 2).sum())
    )
    energy_noise = {
        b: _ratio(float(e_var[b][keep].sum()), float((e_data[b][keep] ** 2).sum())) for b in e_var
    }
    return energy, energy_noise


def _planar_result(sums: dict, energy: dict, energy_noise: dict, grid, map_radius: float) -> PlanarErrors:
    """The relative errors of the summed squares: overall, per band, beyond the noise, per point and pixel."""
    err2, ref2, var = sums["err2"], sums["ref2"], sums["var"]
    pix_err, pix_ref, pix_var = sums["pix_err"], sums["pix_ref"], sums["pix_var"]
    per_point, pt_err2, pt_ref2, pt_var = sums["per_point"], sums["pt_err2"], sums["pt_ref2"], sums["pt_var"]
    tot_e, tot_r, tot_v = sum(err2.values()), sum(ref2.values()), sum(var.values())
    safe = np.where(pix_ref > 0, pix_ref, 1.0)
    per_pixel = np.where(pix_ref > 0, np.sqrt(pix_err / safe), np.nan)
    per_pixel_noise = np.where(pix_ref > 0, np.sqrt(pix_var / safe), np.nan)
    pt_safe = np.where(pt_ref2 > 0, pt_ref2, 1.0)
    per_point_noise = np.where(np.isfinite(per_point), np.sqrt(pt_var / pt_safe), np.nan)
    per_point_beyond = np.where(np.isfinite(per_point), beyond(pt_err2, pt_var, pt_safe), np.nan)
    return PlanarErrors(
        rel_l2=_ratio(tot_e, tot_r),
        bands={b: _ratio(err2[b], ref2[b]) for b in BANDS},
        noise={"all": _ratio(tot_v, tot_r), **{b: _ratio(var[b], ref2[b]) for b in BANDS}},
        energy=energy,
        per_point=per_point,
        per_pixel=per_pixel.reshape(grid.shape),
        grid=grid,
        map_radius=map_radius,
        beyond_noise={
            "all": beyond(tot_e, tot_v, tot_r),
            **{b: beyond(err2[b], var[b], ref2[b]) for b in BANDS},
        },
        energy_noise=energy_noise,
        per_point_noise=per_point_noise,
        per_pixel_noise=per_pixel_noise.reshape(grid.shape),
        per_point_beyond=per_point_beyond,
        per_pixel_beyond=beyond(pix_err, pix_var, pix_ref).reshape(grid.shape),
    )


def _chunk_sums(model, dataset, common, s: int, e: int) -> dict:
    """One chunk of points [s, e): its squared errors, data and variances summed per band, its points'
    energies per band and errors, and its pixels' sums for the maps (packed: only the box under its
    windows).  ``dataset``: an open data set, or its path (a task on a worker opens it itself)."""
    x_i, origin, grid, exclusion, flagged, map_radius = common
    ds = dataset if isinstance(dataset, PlanarDataset) else open_dataset(dataset)
    k = e - s
    y = ds.read("R_d", s, e).astype(np.float64).reshape(k, -1, 3)
    v = ds.read("variance", s, e).astype(np.float64).reshape(k, -1, 3)
    mask = ds.read("mask", s, e).reshape(k, -1)
    geom = window_geometry(x_i[s:e], origin[s:e], grid, ds.window)
    r = np.broadcast_to(geom.r, mask.shape)
    pred = model.R_d_window(np.arange(s, e), origin[s:e], ds.pitch, ds.window).reshape(k, -1, 3)
    ok = mask & np.isfinite(y).all(2) & np.isfinite(v).all(2) & (r >= exclusion) & ~flagged[s:e, None]
    d2 = np.where(ok, ((pred - y) ** 2).sum(2), 0.0)
    y2 = np.where(ok, (y**2).sum(2), 0.0)
    v2 = np.where(ok, v.sum(2), 0.0)
    area = ds.pitch**2
    p_sum = np.where(ok, pred.sum(2), 0.0) * area  # (k, J): energy per pixel, RGB summed
    y_sum = np.where(ok, y.sum(2), 0.0) * area
    v_sum = v2 * area**2  # variance of each pixel's energy
    out = {"err2": {}, "ref2": {}, "var": {}, "energy": {}}
    for b, (lo, hi) in BANDS.items():
        sel = (r >= lo) & (r < hi)
        out["err2"][b] = float(d2[sel].sum())
        out["ref2"][b] = float(y2[sel].sum())
        out["var"][b] = float(v2[sel].sum())
        out["energy"][b] = tuple(np.where(sel, x, 0.0).sum(1) for x in (p_sum, y_sum, v_sum))
    out["energy"]["window"] = (p_sum.sum(1), y_sum.sum(1), v_sum.sum(1))
    den = y2.sum(1)
    rel = np.where(den > 0, np.sqrt(d2.sum(1) / np.where(den > 0, den, 1.0)), np.nan)
    out["per_point"] = (d2.sum(1), den, v2.sum(1), rel)
    n_px = grid.shape[0] * grid.shape[1]
    near = r < map_radius
    for name, x in (("pix_err", d2), ("pix_ref", y2), ("pix_var", v2)):
        out[name] = compact(np.bincount(geom.pixel[near], x[near], minlength=n_px))
    return out


def _chunk_sums_in_order(model, ds, ranges, common, scheduler):
    """Each chunk's :func:`_chunk_sums`, yielded in chunk order: computed here one after the other
    (``threads``), or as tasks on a Dask cluster (``local:N``, ``tcp://…``, an open Cluster) that open
    the data set themselves; a chunk finished early waits until those before it are handed over, so
    the sums are added in the same order and the result is the same wherever the work ran."""
    with open_cluster(scheduler) as cluster:
        if cluster is None:
            for s, e in ranges:
                yield _chunk_sums(model, ds, common, s, e)
            return
        shared = (cluster.keep(model), str(ds.path), cluster.keep(common))
        held, nxt = {}, 0
        window = in_order_window(cluster.n_workers)
        for i, sums in cluster.run(_chunk_sums, ranges, shared=shared, name="evaluate", window=window):
            held[i] = sums
            while nxt in held:
                yield held.pop(nxt)
                nxt += 1
