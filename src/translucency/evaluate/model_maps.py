"""Maps of what the models fitted: the modulation texture α and the parameters over the incident points."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._plotting import pyplot
from ._figures import draw_directions, point_map, save_figure
from .directions import spread_directions
from .labels import model_label


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
    save_figure(fig, Path(path))


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
            im = point_map(ax, x, v, cmap="viridis", vmin=lo, vmax=hi if hi > lo else lo + 1e-12)
            if title.startswith("anisotropy"):
                draw_directions(ax, models[name], x, colour="w")
            ax.set_title(f"{name}: {title}", fontsize=8)
            fig.colorbar(im, ax=ax, shrink=0.8, extend="both")
    fig.tight_layout()
    save_figure(fig, Path(path))
