"""The evaluation report of planar fits: the paper's Figure 1 and the numbers behind it.

:func:`write_report` takes one or more fitted models of the same data set and
writes, into a directory:

``profiles.png``     ring-averaged R_d around chosen incident points, measured and
                     every model, log scale (Figure 1, left);
``error_maps.png``   relative error per outgoing pixel and per incident point of
                     every model, one colour scale with a colour bar (Figure 1, right);
``alpha.png``        the modulation texture α of every model;
``params.png``       maps of the first model's parameters over the incident points;
``report.json``      rel_l2 overall and per band (near < 1 mm, mid 1–4 mm, far > 4 mm),
                     noise floors, flagged points, per model;
``index.html``       all of it side by side.
"""

from __future__ import annotations

import html
import os
import shlex
import sys
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from .._plotting import pyplot
from .._version import __version__
from ..cluster import open_cluster
from ..io.atomic import atomic_path, write_json
from ..io.dataset import PlanarDataset, open_dataset
from ..model.bounds import check_physics
from .errors import BANDS, PlanarErrors, finite_or_null, planar_errors


def model_label(model) -> str:
    """A short name: 'iso n=3 (shared colour)', 'aniso m=8 n=3', 'dipole', 'burley'."""
    if model.kind != "exponential":
        return model.kind
    shape = "iso" if model.n_directions == 1 else f"aniso m={model.n_directions}"
    return f"{shape} n={model.n_terms}" + (" (shared colour)" if model.colour == "shared" else "")


def default_points(n_points: int) -> list[int]:
    """Four incident points spread over a square grid: centre, two off-centre, a corner."""
    side = int(round(np.sqrt(n_points)))
    picks = [
        side // 2 * side + side // 2,
        side // 4 * side + 3 * side // 4,
        3 * side // 4 * side + side // 4,
        0,
    ]
    return sorted({min(p, n_points - 1) for p in picks})


def _save(fig, path: Path) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    pyplot().close(fig)


def ring_stats(window: np.ndarray, variance: np.ndarray | None, pitch: float):
    """Ring means of a (H, W) window centred on x_i and the standard error of each mean.

    The rings of :func:`~translucency.evaluate.measured.ring_profile` (one pixel wide, r ≥ one pixel);
    the error is sqrt(Σ σ²)/n of the ring's pixels (zeros without a variance).
    """
    h, w = window.shape
    yy, xx = np.mgrid[0:h, 0:w]
    ring = np.round(np.hypot(xx - w // 2, yy - h // 2)).astype(int).ravel()
    n = min(h, w) // 2 + 1
    cnt = np.bincount(ring, minlength=n)[:n]
    sums = np.bincount(ring, window.ravel(), minlength=n)[:n]
    var = np.zeros(n) if variance is None else np.bincount(ring, variance.ravel(), minlength=n)[:n]
    keep = (np.arange(n) >= 1) & (cnt > 0)
    c = cnt[keep]
    return np.arange(n)[keep] * pitch, sums[keep] / c, np.sqrt(var[keep]) / c


def model_rings(model, point: int, edges: np.ndarray, channel: int = 1, samples: int = 8, angles: int = 64):
    """Area-weighted mean of a model's R_d (α(x_o) included) over each ring [edges[j], edges[j+1]) around
    its incident point ``point``: the ring means of a fine radial grid."""
    x0 = np.asarray(model.x_i[point, :2], dtype=np.float64)
    lo, hi = edges[:-1], edges[1:]
    t = (np.arange(samples) + 0.5) / samples
    r = lo[:, None] + (hi - lo)[:, None] * t[None, :]  # (J, S)
    phi = 2 * np.pi * (np.arange(angles) + 0.5) / angles
    xo = x0 + np.stack([r[..., None] * np.cos(phi), r[..., None] * np.sin(phi)], axis=-1)  # (J, S, A, 2)
    vals = model.R_d(np.full(xo[..., 0].size, point), xo.reshape(-1, 2))[:, channel].reshape(
        r.shape + (angles,)
    )
    return (vals.mean(axis=2) * r).sum(axis=1) / r.sum(axis=1)


def _residual_axes(ax, r, noise, lim_from, label: str) -> None:
    ax.fill_between(r, -noise, noise, color="0.8", lw=0, label="truth's noise (±1σ)")
    ax.axhline(0.0, color="k", lw=0.8)
    finite = np.concatenate([np.abs(v[np.isfinite(v)]) for v in lim_from] or [np.zeros(1)])
    lim = float(np.clip(1.15 * finite.max() if finite.size else 0.1, 0.05, 1.5))
    ax.set_ylim(-lim, lim)
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)


def plot_profiles(
    models: dict,
    ds: PlanarDataset,
    points: list[int],
    path,
    channel: int = 1,
    *,
    fitted: PlanarDataset | None = None,
    fine: dict | None = None,
    exclusion: dict | None = None,
) -> None:
    """Figure 1 (left): ring means of the reference (``ds``: the truth when there is one) and of every
    model around each point, log scale, with a residual panel (model / reference − 1) and the reference's
    noise band beneath; with ``fine`` (ring profiles on a fine radial grid, see
    :func:`translucency.pipeline.fine_profiles`) two more rows show the first millimetres at that
    resolution — where the dipole starts too high and falls too steeply."""
    plt = pyplot()
    rows = 2 + (2 if fine is not None else 0)
    fig, axes = plt.subplots(
        rows,
        len(points),
        figsize=(4.2 * len(points), 2.6 * rows + 0.6),
        squeeze=False,
        gridspec_kw={"height_ratios": [2.2, 1.0] * (rows // 2)},
    )
    origin = ds["window_origin"]
    colours = {name: f"C{k}" for k, name in enumerate(models)}
    ref_label = "truth (independent acquisition)" if fitted is not None else "measured (virtual DISCO)"
    x_i = ds["x_i"]
    for j, p in enumerate(points):
        ax, res = axes[0][j], axes[1][j]
        y = np.asarray(ds.group["R_d"][p, :, :, channel], dtype=np.float64)
        v = np.asarray(ds.group["variance"][p, :, :, channel], dtype=np.float64)
        r, ym, ys = ring_stats(y, v, ds.pitch)
        if fitted is not None:
            fy = np.asarray(fitted.group["R_d"][p, :, :, channel], dtype=np.float64)
            _, fm, _ = ring_stats(fy, None, ds.pitch)
            ax.semilogy(r, np.where(fm > 0, fm, np.nan), ".", color="0.6", ms=4, label="fitted data")
        ax.errorbar(r, np.where(ym > 0, ym, np.nan), yerr=ys, fmt="ko", ms=3, lw=0.8, label=ref_label)
        ax.set_yscale("log")
        resid = []
        for name, m in models.items():
            pred = m.R_d_window([p], origin[p : p + 1], ds.pitch, ds.window)[0, :, :, channel]
            _, pm, _ = ring_stats(pred, None, ds.pitch)
            style = "-" if m.kind == "exponential" else "--"
            ax.semilogy(r, pm, style, color=colours[name], lw=1.5, label=name)
            rel = np.where(ym > 0, pm / np.where(ym > 0, ym, 1.0) - 1.0, np.nan)
            res.plot(r, rel, style, color=colours[name], lw=1.3)
            resid.append(rel[r < 3.0])
        noise = np.where(ym > 0, ys / np.where(ym > 0, ym, 1.0), np.nan)
        _residual_axes(
            res, r, noise, resid, "model / truth − 1" if fitted is not None else "model / data − 1"
        )
        ax.set_title(f"x_i #{p} at ({x_i[p][0]:.2f}, {x_i[p][1]:.2f}) mm, {ds.pitch:g} mm pixels", fontsize=9)
        ax.set_ylabel("$R_d$ [mm$^{-2}$], " + "RGB"[channel])
        ax.grid(alpha=0.3, which="both")
        res.set_xlabel("r [mm]")
        if fine is not None:
            k = list(np.asarray(fine["points"])).index(p) if p in list(np.asarray(fine["points"])) else None
            fax, fres = axes[2][j], axes[3][j]
            if k is None:
                fax.set_visible(False)
                fres.set_visible(False)
                continue
            edges = np.asarray(fine["edges_mm"], dtype=np.float64)
            rc = 0.5 * (edges[1:] + edges[:-1])
            fy = np.asarray(fine["R_d"], dtype=np.float64)[k, :, channel]
            fs = np.sqrt(np.asarray(fine["variance"], dtype=np.float64)[k, :, channel])
            fax.errorbar(
                rc,
                np.where(fy > 0, fy, np.nan),
                yerr=fs,
                fmt="ko",
                ms=2.5,
                lw=0.8,
                label=f"truth, {edges[1] - edges[0]:g} mm rings",
            )
            fresid = []
            for name, m in models.items():
                pm = model_rings(m, p, edges, channel)
                style = "-" if m.kind == "exponential" else "--"
                fax.semilogy(rc, pm, style, color=colours[name], lw=1.5, label=name)
                rel = np.where(fy > 0, pm / np.where(fy > 0, fy, 1.0) - 1.0, np.nan)
                fres.plot(rc, rel, style, color=colours[name], lw=1.3)
                fresid.append(rel)
            fax.set_yscale("log")
            excl = max([v for v in (exclusion or {}).values() if v], default=ds.pitch)
            for a in (fax, fres):
                a.axvline(excl, color="0.4", ls=":", lw=1.0)
            fax.text(
                excl,
                0.03,
                f" fits use r ≥ {excl:g} mm",
                transform=fax.get_xaxis_transform(),
                fontsize=7,
                color="0.3",
            )
            fax.set_title(f"near x_i #{p}: fine rings ({int(fine['photons']):,} photons)", fontsize=9)
            fax.set_ylabel("$R_d$ [mm$^{-2}$], " + "RGB"[channel])
            fax.grid(alpha=0.3, which="both")
            fnoise = np.where(fy > 0, fs / np.where(fy > 0, fy, 1.0), np.nan)
            _residual_axes(fres, rc, fnoise, fresid, "model / truth − 1")
            fres.set_xlabel("r [mm]")
    axes[0][0].legend(fontsize=7)
    axes[1][0].legend(fontsize=7, loc="lower right")
    if fine is not None:
        axes[2][0].legend(fontsize=7)
    fig.tight_layout()
    _save(fig, Path(path))


def spread_directions(model, channel: int = 1, radius: float = 2.0):
    """Per incident point of an anisotropic exponential model: the direction (radians from x) along which
    its R_d spreads farthest within ``radius`` mm, and the ratio of the rms radii along and across it.

    Direction l's profile P_l(r) = Σ_k c_kl e^{d_kl r} gives ρ_l² = ∫ r² P_l r dr / ∫ P_l r dr over
    r ≤ ``radius`` (the fitted range, where the terms are measured rather than extrapolated); the tensor
    Σ_l ρ_l² u_l u_lᵀ (u_l at θ_l) gives the main axis and the ratio sqrt(λ₁/λ₂).  Isotropic models (and
    m < 3, which cannot tell a direction) give angle 0, ratio 1.
    """
    if model.kind != "exponential" or model.n_directions < 3:
        return np.zeros(model.n_points), np.ones(model.n_points)
    c_blk = model.c[:, channel if model.c.shape[1] == 3 else 0]  # (N, m, n)
    d_blk = model.d[:, channel if model.d.shape[1] == 3 else 0]
    r = (np.arange(200) + 0.5) * radius / 200
    prof = np.einsum("lmk,lmkr->lmr", c_blk, np.exp(d_blk[..., None] * r))  # (N, m, R)
    energy = (prof * r).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        rho2 = np.where(energy > 0, (prof * r**3).sum(-1) / np.where(energy > 0, energy, 1), 0.0)
    theta = 2 * np.pi * np.arange(model.n_directions) / model.n_directions
    txx = (rho2 * np.cos(theta) ** 2).sum(-1)
    tyy = (rho2 * np.sin(theta) ** 2).sum(-1)
    txy = (rho2 * np.cos(theta) * np.sin(theta)).sum(-1)
    angle = 0.5 * np.arctan2(2 * txy, txx - tyy)
    half = np.sqrt((0.5 * (txx - tyy)) ** 2 + txy**2)
    mean = 0.5 * (txx + tyy)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.sqrt((mean + half) / np.maximum(mean - half, 1e-300))
    return angle, ratio


def _draw_directions(ax, model, x_i: np.ndarray, *, every: int = 2, colour: str = "cyan") -> None:
    """Segments along each point's main spreading direction, length ∝ (ratio − 1), capped."""
    angle, ratio = spread_directions(model)
    side = int(round(np.sqrt(len(x_i))))
    pick = np.arange(len(x_i))
    if side * side == len(x_i):
        order = np.lexsort((x_i[:, 0], x_i[:, 1])).reshape(side, side)
        pick = order[::every, ::every].ravel()
    spacing = np.min(np.diff(np.unique(x_i[:, 0]))) if len(np.unique(x_i[:, 0])) > 1 else 1.0
    length = np.clip((ratio[pick] - 1.0) / 0.5, 0.0, 1.0) * every * spacing * 0.95  # full cell at 1.5
    u, v = length * np.cos(angle[pick]), length * np.sin(angle[pick])
    ax.quiver(
        x_i[pick, 0],
        x_i[pick, 1],
        u,
        v,
        angles="xy",
        scale_units="xy",
        scale=1,
        pivot="middle",
        headwidth=0,
        headlength=0,
        headaxislength=0,
        color=colour,
        width=0.006,
    )


def _point_map(ax, x_i: np.ndarray, values: np.ndarray, **kw):
    """Values per incident point: a pixel per point on a square scan grid, else squares."""
    side = int(round(np.sqrt(len(x_i))))
    if side * side == len(x_i) and side > 1:
        order = np.lexsort((x_i[:, 0], x_i[:, 1]))
        hx = (x_i[:, 0].max() - x_i[:, 0].min()) / (side - 1) / 2
        hy = (x_i[:, 1].max() - x_i[:, 1].min()) / (side - 1) / 2
        ext = [x_i[:, 0].min() - hx, x_i[:, 0].max() + hx, x_i[:, 1].min() - hy, x_i[:, 1].max() + hy]
        im = ax.imshow(values[order].reshape(side, side), origin="lower", extent=ext, **kw)
    else:
        im = ax.scatter(x_i[:, 0], x_i[:, 1], c=values, s=12, marker="s", **kw)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    return im


def _mark_noise(cbar, values: np.ndarray) -> None:
    """The reference's noise on a colour bar: its median as a cyan line, 10–90 % as a light band."""
    v = values[np.isfinite(values) & (values > 0)]
    if not v.size:
        return
    vmin, vmax = cbar.mappable.norm.vmin, cbar.mappable.norm.vmax
    lo, med, hi = (float(np.clip(t, vmin, vmax)) for t in np.quantile(v, [0.1, 0.5, 0.9]))
    cbar.ax.axhspan(lo, hi, color="cyan", alpha=0.3, lw=0)
    cbar.ax.axhline(med, color="cyan", lw=2.5)


def plot_error_maps(
    errors: dict[str, PlanarErrors], x_i: np.ndarray, path, models: dict | None = None
) -> None:
    """Figure 1 (right): relative error per outgoing pixel (raw, and beyond the reference's noise) and per
    incident point; one logarithmic colour scale per row set by the data (2nd–99th percentile over every
    model), shared across models, with the reference's noise marked on the colour bar; for anisotropic
    models the fitted spreading directions are drawn over the per-point map."""
    plt = pyplot()
    from matplotlib.colors import LogNorm  # matplotlib is loaded by pyplot() above

    names = list(errors)
    has_noise = all(e.per_pixel_beyond is not None for e in errors.values())
    rows = ["per_pixel", "per_pixel_beyond", "per_point"] if has_noise else ["per_pixel", "per_point"]
    titles = {
        "per_pixel": "per outgoing pixel (pairs r < {r:g} mm)",
        "per_pixel_beyond": "per pixel, beyond the truth's noise",
        "per_point": "per incident point, rel_l2 {e:.1f} %",
    }

    def norm_of(keys, noise_key):
        v = np.concatenate([np.ravel(getattr(e, k)) for e in errors.values() for k in keys])
        v = v[np.isfinite(v) & (v > 0)]
        if not v.size:
            return LogNorm(1e-3, 1.0)
        lo, hi = np.quantile(v, [0.02, 0.99])
        noise = getattr(next(iter(errors.values())), noise_key)
        noise = np.ravel(noise)[np.isfinite(np.ravel(noise))] if noise is not None else np.zeros(0)
        if noise.size:  # the noise marks stay on the bar
            lo, hi = min(lo, np.quantile(noise, 0.1) / 1.2), max(hi, np.quantile(noise, 0.9) * 1.2)
        return LogNorm(max(lo, 1e-4), max(hi, 2 * max(lo, 1e-4)))

    keys = ["per_pixel", "per_pixel_beyond"] if has_noise else ["per_pixel"]
    pixel_norm = norm_of(keys, "per_pixel_noise")
    point_norm = norm_of(["per_point"], "per_point_noise")
    fig, axes = plt.subplots(
        len(rows), len(names), figsize=(3.7 * len(names) + 1.6, 3.5 * len(rows)), squeeze=False
    )
    lo, hi = x_i.min(axis=0) - 1.0, x_i.max(axis=0) + 1.0  # the scanned area
    cmap = pyplot().get_cmap("magma").with_extremes(under="black", bad="0.85")
    mappables = {}
    for j, name in enumerate(names):
        e = errors[name]
        h, w = e.grid.shape
        ext = [
            e.grid.origin[0],
            e.grid.origin[0] + w * e.grid.pitch,
            e.grid.origin[1],
            e.grid.origin[1] + h * e.grid.pitch,
        ]
        for row, key in enumerate(rows):
            ax = axes[row][j]
            vals = getattr(e, key)
            if key == "per_point":
                im = _point_map(ax, x_i, np.maximum(vals, 1e-12), cmap=cmap, norm=point_norm)
                if models is not None and getattr(models[name], "n_directions", 1) > 1:
                    _draw_directions(ax, models[name], x_i)
            else:
                shown = np.where(np.isfinite(vals), np.maximum(vals, 1e-12), np.nan)
                im = ax.imshow(shown, origin="lower", extent=ext, cmap=cmap, norm=pixel_norm)
                ax.set_xlabel("x [mm]")
                ax.set_ylabel("y [mm]")
            ax.set_xlim(lo[0], hi[0])
            ax.set_ylim(lo[1], hi[1])
            if j > 0:
                ax.set_ylabel("")
            head = f"{name}\n" if row == 0 else ""
            ax.set_title(head + titles[key].format(r=e.map_radius, e=100 * e.rel_l2), fontsize=9)
            mappables[key] = im
    first = errors[names[0]]
    for row, key in enumerate(rows):
        noise = first.per_point_noise if key == "per_point" else first.per_pixel_noise
        label = "relative L2 error" + (" (black: within noise)" if key.endswith("beyond") else "")
        finite = None if noise is None else np.ravel(noise)[np.isfinite(np.ravel(noise))]
        if finite is not None and finite.size:
            label += f"\ncyan: truth's noise, median {100 * np.median(finite):.1f} %"
        cb = fig.colorbar(mappables[key], ax=axes[row].tolist(), shrink=0.85, extend="both", label=label)
        if finite is not None:
            _mark_noise(cb, finite)
    _save(fig, Path(path))


def plot_error_ratios(
    errors: dict[str, PlanarErrors], x_i: np.ndarray, path, models: dict | None = None
) -> None:
    """Per incident point, each model's error over the first model's (same reference, so the reference's
    noise is in both): below 1 (blue) the model is closer to the reference there; log colour scale 1/3–3."""
    plt = pyplot()
    from matplotlib.colors import LogNorm  # matplotlib is loaded by pyplot() above

    names = list(errors)
    base = names[0]
    others = names[1:]
    fig, axes = plt.subplots(
        1, max(len(others), 1), figsize=(4.0 * max(len(others), 1) + 1.2, 3.9), squeeze=False
    )
    norm = LogNorm(1 / 3, 3)
    im = None
    for ax, name in zip(axes[0], others):
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = errors[name].per_point / errors[base].per_point
        im = _point_map(ax, x_i, ratio, cmap="RdBu_r", norm=norm)
        med = np.nanmedian(ratio) if np.isfinite(ratio).any() else np.nan
        ax.set_title(f"{name} / {base}, per incident point\n(median {med:.2f})", fontsize=9)
        if models is not None and getattr(models[name], "n_directions", 1) > 1:
            _draw_directions(ax, models[name], x_i, colour="k")
    if im is not None:
        fig.colorbar(im, ax=axes[0].tolist(), shrink=0.85, extend="both", label=f"relative error / {base}'s")
    else:
        axes[0][0].set_visible(False)
    _save(fig, Path(path))


def plot_alpha(models: dict, path) -> None:
    """The modulation texture α of each model (dimensionless), one colour scale set by the data."""
    plt = pyplot()
    fig, axes = plt.subplots(1, len(models), figsize=(3.9 * len(models), 3.6), squeeze=False)
    allv = np.concatenate([np.ravel(m.alpha.values) for m in models.values()])
    allv = allv[np.isfinite(allv)]
    vmin, vmax = np.quantile(allv, [0.01, 0.99]) if allv.size else (0.0, 1.0)
    for ax, (name, m) in zip(axes[0], models.items()):
        a = m.alpha
        h, w = a.shape
        ext = [a.origin[0], a.origin[0] + w * a.pitch, a.origin[1], a.origin[1] + h * a.pitch]
        im = ax.imshow(a.values, origin="lower", extent=ext, cmap="gray", vmin=vmin, vmax=vmax)
        ax.set_title(f"α — {name}", fontsize=9)
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        fig.colorbar(im, ax=ax, shrink=0.8, label="α(x_o) [dimensionless]")
    fig.tight_layout()
    _save(fig, Path(path))


def parameter_maps(model) -> dict:
    """The maps of :func:`plot_parameters`: title with unit -> value per incident point."""
    maps = {
        "total diffuse reflectance ρ (G) [–]": model.total_reflectance()[:, 1],
        "99.9 % energy radius [mm]": model.energy_radius(),
    }
    if model.kind == "exponential":
        a = -model.d[:, -1 if model.c.shape[1] == 1 else 1].mean(axis=1)  # (N, n): mean over directions
        for k in range(model.n_terms):
            maps[f"rate $-d_{k + 1}$ (G) [mm$^{{-1}}$]"] = a[:, k]
        if model.colour == "shared":
            maps["$s_g$ [–]"], maps["$s_b$ [–]"] = model.s_g, model.s_b
        if model.n_directions > 1:
            maps["anisotropy: rms radius along / across [–]"] = spread_directions(model)[1]
    elif hasattr(model, "sigma_a") and hasattr(model, "sigma_s_prime"):
        maps["$\\sigma_a$ (G) [mm$^{-1}$]"] = model.sigma_a[:, 1]
        maps["$\\sigma_s'$ (G) [mm$^{-1}$]"] = model.sigma_s_prime[:, 1]
    elif hasattr(model, "A"):
        maps["A (G) [–]"], maps["s (G) [mm$^{-1}$]"] = model.A[:, 1], model.s[:, 1]
    return maps


def plot_parameters(models, path) -> None:
    """Maps over the incident points of each model's parameters, with units; for an anisotropic model
    the fitted spreading directions are drawn over its anisotropy map."""
    plt = pyplot()
    models = models if isinstance(models, dict) else {model_label(models): models}
    all_maps = {name: parameter_maps(m) for name, m in models.items()}
    cols = max(len(v) for v in all_maps.values())
    fig, axes = plt.subplots(len(models), cols, figsize=(3.4 * cols, 3.1 * len(models)), squeeze=False)
    for row, (name, maps) in enumerate(all_maps.items()):
        x = models[name].x_i[:, :2]
        for j in range(cols):
            ax = axes[row][j]
            if j >= len(maps):
                ax.set_visible(False)
                continue
            title, v = list(maps.items())[j]
            v = np.asarray(v, dtype=np.float64)
            fin = v[np.isfinite(v)]
            lo, hi = np.quantile(fin, [0.02, 0.98]) if fin.size else (0.0, 1.0)  # outliers: the bar's ends
            im = _point_map(ax, x, v, cmap="viridis", vmin=lo, vmax=hi if hi > lo else lo + 1e-12)
            if title.startswith("anisotropy"):
                _draw_directions(ax, models[name], x, colour="w")
            ax.set_title(f"{name}: {title}", fontsize=8)
            fig.colorbar(im, ax=ax, shrink=0.8, extend="both")
    fig.tight_layout()
    _save(fig, Path(path))


def _load_fine(fine):
    if fine is None or isinstance(fine, dict):
        return fine
    with np.load(fine) as z:
        return {k: z[k] for k in z.files}


def _relative(path, base: Path) -> str:
    try:
        return os.path.relpath(Path(path).resolve(), base.resolve())
    except ValueError:  # another drive
        return str(path)


def write_report(
    models,
    dataset,
    out_dir,
    *,
    points=None,
    flagged=None,
    json_path=None,
    extra=None,
    truth=None,
    exclusion=None,
    fine=None,
    command: str | None = None,
    scheduler=None,
) -> dict:
    """Evaluate models on a planar data set and write the figures, JSON and HTML report.

    ``scheduler``: where the errors' chunks are computed (``"threads"``, ``"local:N"``,
    ``"tcp://HOST:PORT"`` or an open :class:`translucency.cluster.Cluster`); the report is the same.

    With ``truth`` (an independent acquisition of the same sample and incident points: another photon
    seed, usually more photons) every figure and headline number is against the truth, the error beyond
    the truth's own noise stands beside it, and the in-sample errors (against the data the models were
    fitted to) under ``in_sample``.

    Parameters
    ----------
    models : ReflectanceModel or sequence of them, or dict label -> model
        The first is the primary model (its numbers are also the JSON's top level).
    dataset : PlanarDataset or path
    out_dir : path
        Report directory.
    points : list of int, optional
        Incident points for the profiles; default the points of ``fine``, else :func:`default_points`.
    flagged : dict label -> bool array, optional
        Points each fit flagged (left out of its errors and listed).
    json_path : path, optional
        Also write the JSON summary here.
    extra : list of (file name, caption), optional
        Further figures already in ``out_dir`` to show in the HTML page.
    truth : PlanarDataset or path, optional
        The held-out truth.
    exclusion : dict label -> float, optional
        The exclusion radius (mm) each fit used; pairs closer are not evaluated (default one pixel).
    fine : dict or path (.npz), optional
        Ring profiles of the truth on a fine radial grid around some incident points
        (:func:`translucency.pipeline.fine_profiles`): the near-x_i rows of the profile figure.
    command : str, optional
        The command that made the report (default: this process's command line).

    Returns
    -------
    dict
        The JSON summary; an empty band's numbers are NaN here and null in the files.
    """
    ds = dataset if isinstance(dataset, PlanarDataset) else open_dataset(dataset)
    if not isinstance(models, dict):
        models = list(models) if isinstance(models, (list, tuple)) else [models]
        models = {model_label(m): m for m in models}
    flagged = flagged or {}
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    exclusion = exclusion or {}
    fine = _load_fine(fine)
    truth = None if truth is None else truth if isinstance(truth, PlanarDataset) else open_dataset(truth)
    with open_cluster(scheduler) as cluster:  # one cluster (if any) for every model's errors

        def errors_on(data, name, m):
            return planar_errors(
                m, data, flagged=flagged.get(name), exclusion_mm=exclusion.get(name), scheduler=cluster
            )

        in_sample = {name: errors_on(ds, name, m) for name, m in models.items()}
        held_out = None if truth is None else {name: errors_on(truth, name, m) for name, m in models.items()}
    if truth is None:
        for e in in_sample.values():  # against the fitted data the noise cannot be subtracted
            e.per_pixel_beyond = e.per_point_beyond = None
    errors = held_out or in_sample
    shown = truth or ds
    if points is None:
        points = [int(p) for p in fine["points"]] if fine is not None else default_points(ds.n_points)
    points = list(points)
    plot_profiles(
        models,
        shown,
        points,
        out_dir / "profiles.png",
        fitted=ds if truth is not None else None,
        fine=fine if truth is not None else None,
        exclusion=exclusion,
    )
    plot_error_maps(errors, ds["x_i"], out_dir / "error_maps.png", models=models)
    plot_error_ratios(errors, ds["x_i"], out_dir / "error_ratios.png", models=models)
    plot_alpha(models, out_dir / "alpha.png")
    first = next(iter(models))
    plot_parameters(models, out_dir / "params.png")
    per_model = {}
    for name, e in errors.items():
        per_model[name] = e.summary()
        if held_out is None:
            per_model[name]["beyond_noise"] = None  # in-sample: the fit has followed the noise
        fl = flagged.get(name)
        per_model[name]["flagged_points"] = [] if fl is None else np.flatnonzero(fl).tolist()
        per_model[name]["physics"] = check_physics(models[name]).summary()
        if held_out is not None:
            s_in = in_sample[name].summary()
            s_in.pop("beyond_noise", None)
            per_model[name]["in_sample"] = s_in
    summary = {
        "written_by": f"translucency {__version__}",
        "command_line": command
        if command is not None
        else shlex.join([Path(sys.argv[0]).name, *sys.argv[1:]]),
        "date": datetime.now(UTC).isoformat(timespec="seconds"),
        "dataset": _relative(ds.path, out_dir),
        "truth": None if truth is None else _relative(truth.path, out_dir),
        "paths": "relative to this report's folder",
        "evaluated_against": "truth (independent acquisition)" if truth is not None else "the fitted data",
        "model": first,
        **per_model[first],
        "bands_mm": {k: [lo, hi if np.isfinite(hi) else None] for k, (lo, hi) in BANDS.items()},
        "models": per_model,
        "profile_points": points,
        "fine_profiles": None
        if fine is None
        else {"bin_mm": float(fine["edges_mm"][1] - fine["edges_mm"][0]), "photons": int(fine["photons"])},
        "definition": DEFINITIONS,
    }
    strict = finite_or_null(summary)  # no NaN in the files: an empty band is null
    write_json(out_dir / "report.json", strict)
    if json_path is not None:
        write_json(json_path, strict)
    _write_html(out_dir / "index.html", ds, strict, extra or [])
    return summary


#: what each number of the report means (report.json "definition", the HTML page)
DEFINITIONS = {
    "rel_l2": "||model - reference||_2 / ||reference||_2 over the valid pairs (x_i, x_o) (mask, finite, "
    "r >= the fit's exclusion radius, default one pixel), RGB summed; rel_l2_near/mid/far the same over "
    "r < 1 mm / 1-4 mm / > 4 mm. The reference is the truth when there is one, else the fitted data",
    "noise_floor": "sqrt(sum of the reference's variance) / ||reference||: what a perfect model scores",
    "beyond_noise": "sqrt(max(||model - truth||^2 - sum variance, 0)) / ||truth||: the error left after the "
    "truth's own (independent) noise, an estimate of the error against the noise-free material; "
    "null in-sample",
    "energy_error": "per incident point the energy sum R_d p^2 over a band (near, mid, far) or the whole "
    "window, model against reference, relative L2 over the points; 'total': the model's closed-form total "
    "diffuse reflectance (x mean alpha) against the reference's tally of every exit",
    "energy_noise": "the reference's noise of those energies",
    "in_sample": "the same numbers against the data the model was fitted to",
    "per_point": "median and 95th percentile of the per-incident-point relative error",
}


def _pct(v) -> str:
    return "–" if v is None or not np.isfinite(v) else f"{100 * v:.2f} %"


def _write_html(path: Path, ds: PlanarDataset, summary: dict, extra: list) -> None:
    held_out = summary.get("truth") is not None
    rows = []
    for name, s in summary["models"].items():
        cells = "".join(
            f"<td>{_pct(s[k])}</td>" for k in ("rel_l2", "rel_l2_near", "rel_l2_mid", "rel_l2_far")
        )
        if held_out:
            b = s.get("beyond_noise") or {}
            cells += f"<td>{_pct(b.get('all'))}</td><td>{_pct(b.get('near'))}</td>"
        en = s["energy_error"]
        cells += "".join(f"<td>{_pct(en.get(k))}</td>" for k in ("near", "mid", "total"))
        if held_out:
            cells += f"<td>{_pct(s['in_sample']['rel_l2'])}</td>"
        ph = s["physics"]
        unphysical = len(set(ph["over_albedo"]) | set(ph["beyond_object"]))
        max_rho = ph["max_total_reflectance"]
        rows.append(
            f"<tr><th>{html.escape(name)}</th>{cells}<td>{len(s['flagged_points'])}</td>"
            f"<td>{unphysical} (max ρ {'–' if max_rho is None else f'{max_rho:.3g}'})</td></tr>"
        )
    first = next(iter(summary["models"].values()))
    nf, ne = first["noise_floor"], first.get("energy_noise") or {}
    noise_cells = "".join(f"<td>{_pct(nf.get(k))}</td>" for k in ("all", "near", "mid", "far"))
    if held_out:
        noise_cells += "<td>0</td><td>0</td>"
    noise_cells += f"<td>{_pct(ne.get('near'))}</td><td>{_pct(ne.get('mid'))}</td><td></td>"
    if held_out:
        noise_cells += f"<td>{_pct(first['in_sample']['noise_floor']['all'])}</td>"
    noise_cells += "<td></td><td></td>"
    noise_label = "the truth's own noise" if held_out else "measurement noise alone"
    against = (
        f"an independent acquisition of the same sample and incident points "
        f"(<code>{html.escape(summary['truth'])}</code>); 'in-sample' is against the fitted data"
        if held_out
        else "the data the models were fitted to (in-sample: a model that fits noise scores well here)"
    )
    own_noise = "The last row's in-sample cell is the fitted data's own noise." if held_out else ""
    beyond_head = "<th>beyond noise, all</th><th>beyond noise, near</th>" if held_out else ""
    in_head = "<th>in-sample, all</th>" if held_out else ""
    defs = "".join(
        f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>" for k, v in summary["definition"].items()
    )
    figures = "".join(
        f'<figure><img src="{html.escape(f)}"><figcaption>{html.escape(c)}</figcaption></figure>'
        for f, c in extra
    )
    fine = summary.get("fine_profiles")
    fine_text = (
        ""
        if not fine
        else f" The lower two rows: the truth on {fine['bin_mm']:g} mm rings ({fine['photons']:,} photons "
        "per point and channel) against each model's ring means — the fits saw r ≥ the dotted line only."
    )
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>translucency report</title>
<style>body{{font-family:sans-serif;max-width:1500px;margin:auto}} table{{border-collapse:collapse}}
td,th{{border:1px solid #ccc;padding:4px 8px;text-align:right}} img{{max-width:100%}}</style></head><body>
<h1>Planar fit report</h1>
<p>{html.escape(summary["written_by"])}, {html.escape(summary["date"])}; command
<code>{html.escape(summary["command_line"])}</code>. Paths are relative to this page's folder.</p>
<p>Data set: <code>{html.escape(summary["dataset"])}</code> — {ds.n_points} incident points,
windows {ds.window[0]}×{ds.window[1]} px at {ds.pitch} mm.</p>
<h2>Errors</h2><p>Against {against}. Relative, RGB summed.</p>
<table><tr><th>model</th><th>all</th><th>near &lt; 1 mm</th><th>mid 1–4 mm</th><th>far &gt; 4 mm</th>
{beyond_head}<th>energy, near</th><th>energy, mid</th><th>total reflectance per point</th>{in_head}
<th>flagged points</th><th>unphysical points (ρ &gt; 1 or r<sub>99.9</sub> beyond the sample)</th></tr>
{"".join(rows)}
<tr><th>{noise_label}</th>{noise_cells}</tr></table>
<p style="font-size:90%">{own_noise}</p>
<ul style="font-size:90%">{defs}</ul>
<figure><img src="profiles.png"><figcaption>Figure 1 (left): ring-averaged R_d around chosen incident points
(green channel), log scale; beneath each, model / truth − 1 with the truth's ±1σ noise band (grey).{fine_text}
</figcaption></figure>
<figure><img src="error_maps.png"><figcaption>Figure 1 (right): relative error per outgoing pixel (pairs
within 4 mm), the same beyond the truth's noise (black: within the noise), and per incident point; one
logarithmic colour scale per row, shared across models, set by the data; the truth's noise marked on each
colour bar (cyan line: its median, cyan band: 10–90 %). Segments on an anisotropic model's map: its fitted
direction of farthest spread, length ∝ (rms radius along / across − 1).</figcaption></figure>
<figure><img src="error_ratios.png"><figcaption>Each model's error per incident point over the first
model's (blue: lower, red: higher; the reference's noise is in both), with an anisotropic model's fitted
directions.</figcaption></figure>
<figure><img src="alpha.png"><figcaption>Modulation texture α (dimensionless), one colour scale.
</figcaption></figure>
<figure><img src="params.png"><figcaption>Parameters of every model over the incident points, with units
(G: green channel).</figcaption></figure>
{figures}
</body></html>
"""
    with atomic_path(path) as tmp:
        tmp.write_text(page)
