r"""Relighting a planar sample with a fitted model, and the check against photon transport.

Under an irradiance pattern :math:`E` (normal incidence) the diffuse radiant
exitance is the superposition of the responses to each incident cell,

.. math:: B(\vec x_o) = \sum_i E(\vec x_i)\, A_i\, R_d(\vec x_i, \vec x_o)
                     = \alpha(\vec x_o) \sum_i E_i A_i P_i(\vec x_o),

with :math:`A_i` the area of the cell around :math:`\vec x_i` (mm²) —
exactly the quantity the virtual acquisition measures under the same pattern
(:func:`translucency.acquire.pattern.acquire_pattern`).  Shadow edges and
stripes show what the model gets wrong: light carried across the boundary.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.image as mpimg
import numpy as np

from .._plotting import pyplot
from .._validate import TranslucencyError
from ._figures import save_figure

PATTERNS = ("edge", "stripe", "spot")


def pattern_irradiance(pattern: str | Path, x_i: np.ndarray) -> np.ndarray:
    """Irradiance (W/mm², RGB) on each incident point for a named pattern or an image.

    ``edge``: the half x < centre lit; ``stripe``: a band 2 mm wide through the
    centre along y; ``spot``: a disc of 2 mm radius at the centre; a path to a
    PNG: its linear RGB (sRGB decoded) stretched over the incident points' extent.

    Examples
    --------
    >>> x = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    >>> pattern_irradiance("edge", x)[:, 0]
    array([1., 0., 0.])
    """
    lo, hi = x_i.min(axis=0), x_i.max(axis=0)
    centre = (lo + hi) / 2
    if str(pattern) in PATTERNS:
        if pattern == "edge":
            lit = x_i[:, 0] < centre[0]
        elif pattern == "stripe":
            lit = np.abs(x_i[:, 0] - centre[0]) < 1.0
        else:
            lit = np.hypot(*(x_i - centre).T) < 2.0
        return np.repeat(lit.astype(float)[:, None], 3, axis=1)
    path = Path(pattern)
    if not path.exists():
        raise TranslucencyError(
            f"pattern: {pattern!r} is neither one of {', '.join(PATTERNS)} nor an image file"
        )
    try:
        img = np.asarray(mpimg.imread(path), dtype=np.float64)
    except Exception as exc:  # noqa: BLE001
        raise TranslucencyError(f"{path}: not a readable image ({type(exc).__name__})") from None
    img = img[..., :3] if img.ndim == 3 else np.repeat(img[..., None], 3, axis=2)
    if img.max() > 1.0:
        img = img / 255.0
    lin = np.where(img <= 0.04045, img / 12.92, ((img + 0.055) / 1.055) ** 2.4)  # sRGB → linear
    h, w = lin.shape[:2]
    u = (x_i - lo) / np.maximum(hi - lo, 1e-9)
    col = np.clip(np.round(u[:, 0] * (w - 1)).astype(int), 0, w - 1)
    row = np.clip(np.round((1 - u[:, 1]) * (h - 1)).astype(int), 0, h - 1)  # image rows run downwards
    return lin[row, col]


def relight(
    model,
    E: np.ndarray,
    cell_area: float,
    origin,
    pitch: float,
    shape: tuple[int, int],
    *,
    radius: float | None = None,
    chunk: int = 64,
) -> np.ndarray:
    """Predict the diffuse radiant exitance of a planar model under irradiance E.

    Parameters
    ----------
    model : ReflectanceModel
        A planar model.
    E : ndarray, shape (N, 3)
        Irradiance on each incident point's cell (W/mm²).
    cell_area : float
        :math:`A_i`, the area each incident point stands for (mm²).
    origin, pitch, shape
        The output pixel grid.
    radius : float, optional
        Truncation radius (mm); default the model's 99.9 % energy radius.

    Returns
    -------
    B : ndarray, shape (H, W, 3)
    """
    h, w = shape
    B = np.zeros((h, w, 3))
    rad = float(np.max(model.energy_radius())) if radius is None else float(radius)
    half = int(np.ceil(rad / pitch))
    lit = np.flatnonzero((np.asarray(E) > 0).any(axis=1))
    origin = np.asarray(origin, dtype=np.float64)
    for s in range(0, lit.size, chunk):
        idx = lit[s : s + chunk]
        # a (2 half + 1)² window of output pixels around each incident point
        c0 = np.floor((model.x_i[idx, 0] - origin[0]) / pitch).astype(int) - half
        r0 = np.floor((model.x_i[idx, 1] - origin[1]) / pitch).astype(int) - half
        win_origin = origin + pitch * np.stack([c0, r0], axis=1)
        Rw = model.R_d_window(idx, win_origin, pitch, (2 * half + 1, 2 * half + 1))
        contrib = Rw * (np.asarray(E)[idx] * cell_area)[:, None, None, :]
        rows = r0[:, None, None] + np.arange(2 * half + 1)[None, :, None]
        cols = c0[:, None, None] + np.arange(2 * half + 1)[None, None, :]
        rows, cols = np.broadcast_arrays(rows, cols)
        ok = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
        flat = rows[ok] * w + cols[ok]
        for channel in range(3):
            B[..., channel] += np.bincount(flat, contrib[..., channel][ok], minlength=h * w).reshape(h, w)
    return B


def plot_relighting(reference: np.ndarray, predictions: dict, extent, path, channel: int = 1) -> dict:
    """Reference | each model | relative difference, and a profile across the middle row.

    The exitance B (W/mm² under the pattern's 1 W/mm² on lit cells) of the reference and every model on
    one colour scale with its colour bar; the differences over the reference's bright level (its 90th
    percentile) on one diverging scale with its colour bar.

    Returns the relative L2 error of each prediction (over the pixels where the reference is lit).
    """
    plt = pyplot()

    ref = reference[..., channel]
    n = len(predictions)
    rgb = "RGB"[channel]
    fig, axes = plt.subplots(  # constrained: the colour bars take their room beside their row
        2, n + 1, figsize=(3.8 * (n + 1) + 1.2, 7.0), squeeze=False, layout="constrained"
    )
    vmax = float(np.quantile(ref, 0.995))
    shown = axes[0][0].imshow(ref, origin="lower", extent=extent, cmap="inferno", vmin=0, vmax=vmax)
    axes[0][0].set_title("photon transport (reference)", fontsize=9)
    errors = {}
    mid = ref.shape[0] // 2
    band = slice(max(mid - 2, 0), mid + 3)
    xs = (
        np.linspace(extent[0], extent[1], ref.shape[1], endpoint=False)
        + (extent[1] - extent[0]) / ref.shape[1] / 2
    )
    axes[1][0].semilogy(xs, ref[band].mean(0), "k.", ms=3, label="reference")
    diff_im = None
    for j, (name, B) in enumerate(predictions.items(), start=1):
        pred = B[..., channel]
        errors[name] = float(np.linalg.norm(B - reference) / np.linalg.norm(reference))
        axes[0][j].imshow(pred, origin="lower", extent=extent, cmap="inferno", vmin=0, vmax=vmax)
        axes[0][j].set_title(f"{name} (rel_l2 {100 * errors[name]:.1f} %)", fontsize=9)
        diff = (pred - ref) / np.maximum(np.quantile(ref, 0.9), 1e-30)
        diff_im = axes[1][j].imshow(diff, origin="lower", extent=extent, cmap="coolwarm", vmin=-0.2, vmax=0.2)
        axes[1][j].set_title(f"({name} − reference) / bright level", fontsize=9)
        axes[1][0].semilogy(xs, pred[band].mean(0), "-", lw=1.5, label=name)
    for ax in axes.ravel():
        ax.set_xlabel("x [mm]")
    for row in axes:
        row[0].set_ylabel("y [mm]")
    fig.colorbar(shown, ax=axes[0].tolist(), shrink=0.85, label=f"exitance B, {rgb} [W mm$^{{-2}}$]")
    if diff_im is not None:
        fig.colorbar(
            diff_im,
            ax=axes[1][1:].tolist(),
            shrink=0.85,
            extend="both",
            label="(model − reference) / bright level",
        )
    axes[1][0].set_title("profile across the middle rows", fontsize=9)
    axes[1][0].set_ylabel(f"exitance B, {rgb} [W mm$^{{-2}}$]")
    axes[1][0].legend(fontsize=7)
    save_figure(fig, Path(path), dpi=100)
    return errors
