r"""Radial profiles of measured windows: ring means around the incident point.

A window centred on x_i is averaged over rings of one pixel width; the pixel
under the beam (r = 0) is left out, as the fits' exclusion radius does.
"""

from __future__ import annotations

import numpy as np


def ring_profile(window: np.ndarray, pitch: float) -> tuple[np.ndarray, np.ndarray]:
    """Ring means of a (H, W) window centred on x_i: (r in mm, mean R_d), r >= one pixel."""
    h, w = window.shape
    yy, xx = np.mgrid[0:h, 0:w]
    r = np.hypot(xx - w // 2, yy - h // 2) * pitch
    ring = np.round(r / pitch).astype(int)
    n_rings = min(h, w) // 2 + 1
    sums = np.bincount(ring.ravel(), window.ravel(), minlength=n_rings)[:n_rings]
    cnt = np.bincount(ring.ravel(), minlength=n_rings)[:n_rings]
    radii = np.arange(n_rings) * pitch
    keep = (np.arange(n_rings) >= 1) & (cnt > 0)
    return radii[keep], sums[keep] / cnt[keep]
