"""A corrected image resampled onto a window of the sample plane through the homography (step 3 of
:mod:`.importer`): area-weighted means of bilinear reads, the variance of the mean, the mask."""

from __future__ import annotations

import numpy as np

from .calibration import Calibration
from .frames import Frame
from .setup import ImportSetup


def resample_window(
    frame: Frame, calib: Calibration, setup: ImportSetup, x_i, origin
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One window (n, n, 3) of R_d·scale·power (pixel values per unit area), its variance and mask."""
    n = setup.window_pixels()
    p = setup.pitch
    centre = np.asarray(origin, float) + 0.5 * n * p
    dense = p * np.sqrt(float(calib.homography.pixels_per_mm2(centre[None])[0]))  # image px per pitch
    # at least one sub-sample per image pixel: every pixel under the window counts (and the variance of
    # the mean is that of n_eff independent pixels)
    s = max(int(setup.supersample), int(np.ceil(dense)))
    sub = (np.arange(n * s) + 0.5) * (p / s)  # sub-sample positions inside the window, mm
    X, Y = np.meshgrid(origin[0] + sub, origin[1] + sub)
    xy = np.stack([X.ravel(), Y.ravel()], axis=1)
    uv = calib.homography.to_image(xy)
    Hh, Ww = frame.value.shape[:2]
    u, v = uv[:, 0], uv[:, 1]
    inside = (u >= 0) & (u <= Ww - 1) & (v >= 0) & (v <= Hh - 1)
    j0 = np.clip(np.floor(u), 0, Ww - 2).astype(np.int64)
    i0 = np.clip(np.floor(v), 0, Hh - 2).astype(np.int64)
    fu = np.clip(u - j0, 0, 1).astype(np.float32)[:, None]
    fv = np.clip(v - i0, 0, 1).astype(np.float32)[:, None]
    # value, variance and bad pixels in one table: four gathers by flat index, one bilinear blend
    table = np.concatenate([frame.value, frame.variance, frame.bad[..., None]], axis=2).reshape(-1, 7)
    k = i0 * Ww + j0
    a, b = table.take(k, axis=0), table.take(k + 1, axis=0)
    c, d = table.take(k + Ww, axis=0), table.take(k + Ww + 1, axis=0)
    mix = (a * (1 - fu) + b * fu) * (1 - fv) + (c * (1 - fu) + d * fu) * fv
    val, var = mix[:, :3], mix[:, 3:6]
    # a bad pixel spoils every read that gives it weight (at an exact pixel centre its neighbours have none)
    bad = (mix[:, 6] > 0) | ~inside
    ppm = calib.homography.pixels_per_mm2(xy).astype(np.float32)  # image pixels per mm² of sample
    if calib.pixel == "flux":  # power per pixel → power per mm²
        val = val * ppm[:, None]
        var = var * (ppm * ppm)[:, None]
    if setup.specular_radius > 0:
        bad |= np.hypot(xy[:, 0] - x_i[0], xy[:, 1] - x_i[1]) <= setup.specular_radius
    if setup.sample_size is not None:
        W, H = setup.sample_size
        bad |= (xy[:, 0] < 0) | (xy[:, 0] > W) | (xy[:, 1] < 0) | (xy[:, 1] > H)
    shape = (n, s, n, s)
    val = val.reshape(*shape, 3).mean(axis=(1, 3))
    n_eff = np.maximum(1.0, ppm.reshape(shape).mean(axis=(1, 3)) * p * p)
    var = var.reshape(*shape, 3).mean(axis=(1, 3)) / n_eff[..., None]
    mask = ~bad.reshape(shape).any(axis=(1, 3))
    return val, var, mask


def window_region(calib: Calibration, origin, side: float, shape) -> tuple[int, int, int, int]:
    """Rows v0..v1 and columns u0..u1 of the image under a window (+2 pixels for the bilinear reads)."""
    corners = np.array([[0, 0], [side, 0], [side, side], [0, side]]) + origin
    uv = calib.homography.to_image(corners)
    Hh, Ww = shape[:2]
    u0 = int(np.clip(np.floor(uv[:, 0].min()) - 2, 0, Ww - 2))
    v0 = int(np.clip(np.floor(uv[:, 1].min()) - 2, 0, Hh - 2))
    u1 = int(np.clip(np.ceil(uv[:, 0].max()) + 3, u0 + 2, Ww))
    v1 = int(np.clip(np.ceil(uv[:, 1].max()) + 3, v0 + 2, Hh))
    return v0, v1, u0, u1


def crop_calibration(calib: Calibration, region) -> Calibration:
    """The calibration's homography for a crop starting at row v0, column u0."""
    v0, _, u0, _ = region
    shift = np.array([[1, 0, -u0], [0, 1, -v0], [0, 0, 1.0]])
    return Calibration(type(calib.homography)(shift @ calib.homography.matrix), calib.scale, calib.pixel)
