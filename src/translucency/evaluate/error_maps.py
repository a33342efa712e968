"""Figure 1 (right): relative error maps per outgoing pixel and per incident point, and error ratios."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._plotting import pyplot
from ._figures import draw_directions, log_ticks, mark_noise, point_map, save_figure
from .errors import PlanarErrors
from .labels import noise_label


def plot_error_maps(
    errors: dict[str, PlanarErrors],
    x_i: np.ndarray,
    path,
    models: dict | None = None,
    *,
    held_out: bool | None = None,
) -> None:
    """Figure 1 (right): relative error per outgoing pixel (raw, and beyond the reference's noise) and per
    incident point; one logarithmic colour scale per row set by the data (2nd–99th percentile over every
    model), shared across models, with the reference's noise marked on the colour bar; for anisotropic
    models the fitted spreading directions are drawn over the per-point map.  ``held_out``: whether the
    reference is an independent truth (default: whether the errors beyond its noise are there), which
    names the noise on the colour bars."""
    plt = pyplot()
    names = list(errors)
    has_noise = all(e.per_pixel_beyond is not None for e in errors.values())
    noise_name = noise_label(has_noise if held_out is None else held_out)
    rows = ["per_pixel", "per_pixel_beyond", "per_point"] if has_noise else ["per_pixel", "per_point"]
    titles = {
        "per_pixel": "per outgoing pixel (pairs r < {r:g} mm)",
        "per_pixel_beyond": f"per pixel, beyond {noise_name}",
        "per_point": "per incident point, rel_l2 {e:.1f} %",
    }
    keys = ["per_pixel", "per_pixel_beyond"] if has_noise else ["per_pixel"]
    norms = {
        "pixel": _norm_of(errors, keys, "per_pixel_noise"),
        "point": _norm_of(errors, ["per_point"], "per_point_noise"),
    }
    fig, axes = plt.subplots(  # constrained: titles, axis labels and colour bars do not overlap
        len(rows),
        len(names),
        figsize=(3.7 * len(names) + 1.6, 3.5 * len(rows)),
        squeeze=False,
        layout="constrained",
    )
    lo, hi = x_i.min(axis=0) - 1.0, x_i.max(axis=0) + 1.0  # the scanned area
    cmap = pyplot().get_cmap("magma").with_extremes(under="black", bad="0.85")
    mappables = {}
    for j, name in enumerate(names):
        e = errors[name]
        model = None if models is None else models[name]
        for row, key in enumerate(rows):
            ax = axes[row][j]
            mappables[key] = _draw_map(ax, e, key, x_i, model, cmap, norms)
            ax.set_xlim(lo[0], hi[0])
            ax.set_ylim(lo[1], hi[1])
            if j > 0:
                ax.set_ylabel("")
            head = f"{name}\n" if row == 0 else ""
            ax.set_title(head + titles[key].format(r=e.map_radius, e=100 * e.rel_l2), fontsize=9)
    first = errors[names[0]]
    for row, key in enumerate(rows):
        _colour_bar(fig, axes[row].tolist(), mappables[key], key, first, noise_name)
    save_figure(fig, Path(path))


def _norm_of(errors: dict, keys, noise_key: str):
    """A row's logarithmic colour scale: the 2nd–99th percentile of its positive errors over every model,
    widened to hold the first model's noise (10–90 %)."""
    from matplotlib.colors import LogNorm  # matplotlib is loaded by pyplot() before this is called

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


def _draw_map(ax, e: PlanarErrors, key: str, x_i, model, cmap, norms: dict):
    """One panel: a model's error per incident point (with its directions) or per pixel of the sample."""
    vals = getattr(e, key)
    if key == "per_point":
        im = point_map(ax, x_i, np.maximum(vals, 1e-12), cmap=cmap, norm=norms["point"])
        if model is not None and getattr(model, "n_directions", 1) > 1:
            draw_directions(ax, model, x_i)
        return im
    h, w = e.grid.shape
    ext = [
        e.grid.origin[0],
        e.grid.origin[0] + w * e.grid.pitch,
        e.grid.origin[1],
        e.grid.origin[1] + h * e.grid.pitch,
    ]
    shown = np.where(np.isfinite(vals), np.maximum(vals, 1e-12), np.nan)
    im = ax.imshow(shown, origin="lower", extent=ext, cmap=cmap, norm=norms["pixel"])
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    return im


def _colour_bar(fig, axes: list, mappable, key: str, first: PlanarErrors, noise_name: str) -> None:
    """A row's colour bar with log ticks, the first model's noise marked (cyan: median, 10–90 % band)."""
    noise = first.per_point_noise if key == "per_point" else first.per_pixel_noise
    label = "relative L2 error" + (" (black: within noise)" if key.endswith("beyond") else "")
    finite = None if noise is None else np.ravel(noise)[np.isfinite(np.ravel(noise))]
    if finite is not None and finite.size:
        label += f"\ncyan: {noise_name}, median {100 * np.median(finite):.1f} %"
    cb = fig.colorbar(mappable, ax=axes, shrink=0.85, extend="both", label=label)
    log_ticks(cb)
    if finite is not None:
        mark_noise(cb, finite)


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
        1,
        max(len(others), 1),
        figsize=(4.0 * max(len(others), 1) + 1.2, 3.9),
        squeeze=False,
        layout="constrained",
    )
    norm = LogNorm(1 / 3, 3)
    im = None
    for ax, name in zip(axes[0], others):
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = errors[name].per_point / errors[base].per_point
        im = point_map(ax, x_i, ratio, cmap="RdBu_r", norm=norm)
        if ax is not axes[0][0]:
            ax.set_ylabel("")
        med = np.nanmedian(ratio) if np.isfinite(ratio).any() else np.nan
        ax.set_title(f"{name} / {base}, per incident point\n(median {med:.2f})", fontsize=9)
        if models is not None and getattr(models[name], "n_directions", 1) > 1:
            draw_directions(ax, models[name], x_i, colour="k")
    if im is not None:
        cb = fig.colorbar(
            im, ax=axes[0].tolist(), shrink=0.85, extend="both", label=f"relative error / {base}'s"
        )
        log_ticks(cb, percent=False)
    else:
        axes[0][0].set_visible(False)
    save_figure(fig, Path(path))
