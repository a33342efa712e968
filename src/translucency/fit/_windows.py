r"""Geometry and grouping of the measurement windows of a planar data set.

Every window pixel is a pair :math:`(\vec x_i, \vec x_o)`: its distance
:math:`r = |\vec x_o - \vec x_i|` (mm), its angle :math:`\theta` in the
sample's frame, and its pixel on the sample-wide grid on which the modulation
texture :math:`\alpha(\vec x_o)` lives.

The isotropic objective depends on a pixel only through r, so pixels of equal
r can be merged exactly: for weights :math:`w_j`, coefficients
:math:`\kappa_j` and targets :math:`y_j`,

.. math:: \sum_{j \in g} w_j^2 (\kappa_j f(r_g) - y_j)^2
          = A_g \bigl(f(r_g) - B_g/A_g\bigr)^2 + \text{const},\quad
          A_g = \sum w_j^2 \kappa_j^2,\; B_g = \sum w_j^2 \kappa_j y_j .

Incident points snapped to pixel centres give a few hundred distinct radii
per window instead of thousands of pixels.  Beyond ``r_exact`` radii may
also be merged into rings of width ``radius_step`` (then :math:`r_g` is the
mean radius of the ring — an approximation of relative order
:math:`(a\,\delta r)^2/24` for a term of rate a).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class SampleGrid:
    """The pixel grid covering all windows: α's support.

    Pixel ``[row, col]`` is centred at ``origin + pitch * (col + 1/2, row + 1/2)``.
    """

    origin: np.ndarray  # (2,) mm
    pitch: float
    shape: tuple[int, int]

    @classmethod
    def covering(cls, window_origin: np.ndarray, pitch: float, window: tuple[int, int]) -> "SampleGrid":
        lo = window_origin.min(axis=0)
        span = np.round((window_origin.max(axis=0) - lo) / pitch).astype(int)
        return cls(lo.astype(np.float64), float(pitch), (int(span[1]) + window[0], int(span[0]) + window[1]))

    def offsets(self, window_origin: np.ndarray) -> np.ndarray:
        """(k, 2) integer (row, col) of each window's first pixel on this grid."""
        o = np.round((window_origin - self.origin) / self.pitch).astype(np.int64)
        return o[:, ::-1]


@dataclass
class WindowGeometry:
    """Per-pixel geometry of a chunk of k windows of H × W pixels (J = H·W)."""

    r: np.ndarray  # (k, J) mm
    theta: np.ndarray  # (k, J) rad
    pixel: np.ndarray  # (k, J) flat index on the sample grid


def window_geometry(x_i: np.ndarray, window_origin: np.ndarray, grid: SampleGrid,
                    window: tuple[int, int]) -> WindowGeometry:
    """Distances, angles and sample-grid pixels of every window pixel."""
    h, w = window
    col, row = np.meshgrid(np.arange(w), np.arange(h))
    col, row = col.ravel(), row.ravel()
    dx = window_origin[:, :1] + grid.pitch * (col + 0.5) - x_i[:, :1]
    dy = window_origin[:, 1:] + grid.pitch * (row + 0.5) - x_i[:, 1:]
    off = grid.offsets(window_origin)
    pixel = (off[:, :1] + row) * grid.shape[1] + (off[:, 1:] + col)
    return WindowGeometry(np.hypot(dx, dy), np.arctan2(dy, dx), pixel)


def radius_groups(r: np.ndarray, pitch: float, *, r_exact: float | None = None,
                  radius_step: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Group ids (same shape as r) and the radius of each group (mm).

    Radii equal to 1e-4 pixel are one group; beyond ``r_exact`` (default: all
    exact) radii within rings of ``radius_step`` mm are merged.

    Examples
    --------
    >>> gid, rg = radius_groups(np.array([[0.0, 1.0, 1.0, 1.5]]), 0.5)
    >>> gid.tolist(), rg.tolist()
    ([[0, 1, 1, 2]], [0.0, 1.0, 1.5])
    """
    if r.ndim == 2 and r.shape[0] > 1 and np.allclose(r, r[:1], rtol=0, atol=pitch * 1e-5):
        # windows placed alike around their points (the usual case): group one, share it
        gid, r_g = radius_groups(r[:1], pitch, r_exact=r_exact, radius_step=radius_step)
        return np.broadcast_to(gid, r.shape), r_g
    key = np.round(r / (pitch * 1e-4)).astype(np.int64)
    if radius_step is not None and r_exact is not None:
        far = r > r_exact
        key = np.where(far, np.int64(2**52) + np.floor(r / radius_step).astype(np.int64), key)
    uniq, gid = np.unique(key, return_inverse=True)
    gid = gid.reshape(r.shape)
    r_g = np.bincount(gid.ravel(), r.ravel(), minlength=uniq.size) / np.bincount(gid.ravel(), minlength=uniq.size)
    return gid, r_g


def group_sums(index: np.ndarray, values: np.ndarray, n_bins: int) -> np.ndarray:
    """``bincount`` of values at flat bin indices (both broadcast together)."""
    index, values = np.broadcast_arrays(index, values)
    return np.bincount(index.ravel(), values.ravel(), minlength=n_bins)
