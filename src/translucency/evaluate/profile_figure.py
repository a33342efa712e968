"""Figure 1 (left): ring-averaged R_d around chosen incident points, measured and every model, log scale."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._plotting import pyplot
from ..io.dataset import PlanarDataset
from ._figures import save_figure
from .labels import noise_label
from .rings import model_rings, ring_stats


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


def _residual_axes(ax, r, noise, lim_from, label: str, noise_name: str) -> None:
    ax.fill_between(r, -noise, noise, color="0.8", lw=0, label=f"{noise_name} (±1σ)")
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
    x_i = ds["x_i"]
    for j, p in enumerate(points):
        _profile_column(axes[0][j], axes[1][j], models, ds, p, channel, fitted, colours, origin, x_i)
        if fine is not None:
            _fine_column(axes[2][j], axes[3][j], models, ds, p, channel, fine, colours, exclusion)
    axes[0][0].legend(fontsize=7)
    axes[1][0].legend(fontsize=7, loc="lower right")
    if fine is not None:
        axes[2][0].legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, Path(path))


def _profile_column(ax, res, models, ds, p, channel, fitted, colours, origin, x_i) -> None:
    """Point p's ring means (mm⁻²) of reference, fitted data and every model, and their residuals."""
    ref_label = "truth (independent acquisition)" if fitted is not None else "measured (virtual DISCO)"
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
        res,
        r,
        noise,
        resid,
        "model / truth − 1" if fitted is not None else "model / data − 1",
        noise_label(fitted is not None),
    )
    ax.set_title(f"x_i #{p} at ({x_i[p][0]:.2f}, {x_i[p][1]:.2f}) mm, {ds.pitch:g} mm pixels", fontsize=9)
    ax.set_ylabel("$R_d$ [mm$^{-2}$], " + "RGB"[channel])
    ax.grid(alpha=0.3, which="both")
    res.set_xlabel("r [mm]")


def _fine_column(fax, fres, models, ds, p, channel, fine, colours, exclusion) -> None:
    """Point p's truth on fine rings (mm⁻²) against every model, and their residuals (hidden if absent)."""
    k = list(np.asarray(fine["points"])).index(p) if p in list(np.asarray(fine["points"])) else None
    if k is None:
        fax.set_visible(False)
        fres.set_visible(False)
        return
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
    _exclusion_mark(fax, fres, exclusion, ds.pitch)
    fax.set_title(f"near x_i #{p}: fine rings ({int(fine['photons']):,} photons)", fontsize=9)
    fax.set_ylabel("$R_d$ [mm$^{-2}$], " + "RGB"[channel])
    fax.grid(alpha=0.3, which="both")
    fnoise = np.where(fy > 0, fs / np.where(fy > 0, fy, 1.0), np.nan)
    _residual_axes(fres, rc, fnoise, fresid, "model / truth − 1", noise_label(True))
    fres.set_xlabel("r [mm]")


def _exclusion_mark(fax, fres, exclusion, pitch) -> None:
    """A dotted line at the largest exclusion radius (mm) the fits used, labelled on the profile."""
    excl = max([v for v in (exclusion or {}).values() if v], default=pitch)
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
