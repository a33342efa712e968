"""Helpers shared by the report's figures: saving, maps over the incident points, noise marks, directions."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._plotting import pyplot
from ..io.atomic import atomic_path
from .directions import spread_directions


def save_figure(fig, path: Path, *, dpi: int = 110) -> None:
    """Write ``fig`` to ``path`` (PNG, whole or not at all) and close it."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi)
    pyplot().close(fig)


def draw_directions(ax, model, x_i: np.ndarray, *, every: int = 2, colour: str = "cyan") -> None:
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


def point_map(ax, x_i: np.ndarray, values: np.ndarray, **kw):
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


def mark_noise(cbar, values: np.ndarray) -> None:
    """The reference's noise on a colour bar: its median as a cyan line, 10–90 % as a light band."""
    v = values[np.isfinite(values) & (values > 0)]
    if not v.size:
        return
    vmin, vmax = cbar.mappable.norm.vmin, cbar.mappable.norm.vmax
    lo, med, hi = (float(np.clip(t, vmin, vmax)) for t in np.quantile(v, [0.1, 0.5, 0.9]))
    cbar.ax.axhspan(lo, hi, color="cyan", alpha=0.3, lw=0)
    cbar.ax.axhline(med, color="cyan", lw=2.5)


def log_ticks(cbar, *, percent: bool = True) -> None:
    """Plain labels on a logarithmic colour bar: per cent (``0.1`` → ``10 %``) or the number (``3``), at
    the powers of ten and at 2, 3 and 5 times them."""
    from matplotlib.ticker import FuncFormatter  # matplotlib is loaded by the figure's pyplot()

    def label(v, _pos):
        if v <= 0:
            return ""
        mantissa = v / 10 ** np.floor(np.log10(v) + 1e-9)
        if min(abs(mantissa - k) for k in (1, 2, 3, 5)) > 1e-6:
            return ""
        return f"{100 * v:.3g} %" if percent else f"{v:.3g}"

    cbar.ax.yaxis.set_major_formatter(FuncFormatter(label))
    cbar.ax.yaxis.set_minor_formatter(FuncFormatter(label))
