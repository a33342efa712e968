"""One laser position's image(s) read and corrected in the image: dark frame, flat field, vignetting,
exposure time; their variance from the sensor's noise model and their bad pixels (steps 1–2 of
:mod:`.importer`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.ndimage import binary_dilation

from ..._validate import TranslucencyError
from ..shared.hdr import LDR_SUFFIXES, merge_exposures, read_hdr, read_ldr
from .calibration import Calibration
from .positions import Shot
from .setup import ImportSetup


@dataclass
class Frame:
    """One laser position's image in pixel values per second: value, variance, bad pixels."""

    value: np.ndarray  # (H, W, 3) float32, dark-subtracted, flat/vignetting corrected, per second
    variance: np.ndarray  # (H, W, 3) float32
    bad: np.ndarray  # (H, W) bool: saturated (dilated), under-exposed, not finite


def load_frame(shot: Shot, calib: Calibration, setup: ImportSetup, shape=None, region=None) -> Frame:
    """Read and correct the image(s) of one laser position (see the module's steps 1–2).

    ``region`` (v0, v1, u0, u1): correct only these rows and columns (the part under a window).
    """
    ldr = shot.files[0].suffix.lower() in LDR_SUFFIXES
    v0, v1, u0, u1 = region if region is not None else (0, None, 0, None)
    sl = (slice(v0, v1), slice(u0, u1))
    cut = lambda a: None if a is None else a[sl]  # noqa: E731
    if ldr:
        codes, tops = zip(*(read_ldr(p) for p in shot.files))
        _check_shapes(shot, [c.shape for c in codes], shape)
        times = shot.exposures if len(shot.exposures) == len(codes) else shot.exposures * len(codes)
        value, var, sat, under = merge_exposures(
            [c[sl] for c in codes], times, top=tops[0], gain=calib.gain, read_noise=calib.read_noise
        )
        exposure = 1.0  # the merge is per second already
        bad = sat | under
        if calib.dark is not None:  # a dark frame in codes at the first exposure
            value = value - calib.dark[sl] / np.float32(times[0])
    else:
        frames = [read_hdr(p) for p in shot.files]
        _check_shapes(shot, [f.shape for f in frames], shape)
        for p, f in zip(shot.files, frames):
            if not np.isfinite(f.sum()) and not np.isfinite(f).all():  # one fast pass, then find the pixel
                row, col, channel = (int(i) for i in np.argwhere(~np.isfinite(f))[0])
                raise TranslucencyError(
                    f"{p}: pixel (row {row}, column {col}, channel {channel}) is {f[row, col, channel]}"
                )
        frames = [f[sl] for f in frames]
        bad = np.zeros(frames[0].shape[:2], bool)
        if np.isfinite(calib.saturation):
            for f in frames:
                bad |= (f >= np.float32(calib.saturation)).any(axis=-1)
        if len(frames) == 1:
            value = frames[0]
            var = np.float32(calib.gain) * np.maximum(value, 0) + np.float32(calib.read_noise**2)
        else:  # repeated frames: the mean, and the variance of the mean from their spread
            stack = np.stack(frames)
            value = stack.mean(axis=0)
            var = stack.var(axis=0, ddof=1) / np.float32(len(frames))
        exposure = shot.exposures[0]
        if calib.dark is not None:
            value = value - calib.dark[sl]
        if setup.floor is not None:
            bad |= (value < np.float32(setup.floor)).any(axis=-1)
    if setup.dilate and bad.any():
        bad = binary_dilation(bad, iterations=int(setup.dilate))
    corr = np.full(value.shape[:2] + (1,), 1.0 / exposure, np.float32)
    if len(calib.vignetting):
        full = shape or (value.shape if region is None else None)
        v, u = np.mgrid[0 : value.shape[0], 0 : value.shape[1]]
        corr = corr / calib.falloff(u + u0, v + v0, full)[..., None]
    if calib.flat is not None:
        corr = corr / cut(calib.flat)
    return Frame(value * corr, var * corr * corr, bad)


def _check_shapes(shot: Shot, shapes, shape) -> None:
    want = shape or shapes[0]
    for p, s in zip(shot.files, shapes):
        if tuple(s) != tuple(want):
            raise TranslucencyError(
                f"{p}: image of {s[1]} x {s[0]} pixels among images of {want[1]} x {want[0]} pixels"
            )


def pfm_shape(path: Path) -> tuple[int, int] | None:
    """(H, W) from a PFM header, or None for other files."""
    if path.suffix.lower() != ".pfm":
        return None
    with open(path, "rb") as f:
        words = f.read(64).split()
    try:
        return int(words[2]), int(words[1])
    except (IndexError, ValueError):
        return None


def image_shape(shot: Shot) -> tuple[int, int, int]:
    """(H, W, 3) of a shot's first image (every image of the import must have it)."""
    p = shot.files[0]
    return read_ldr(p)[0].shape if p.suffix.lower() in LDR_SUFFIXES else read_hdr(p).shape
