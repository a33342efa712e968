"""Tone mapping and the picture files: linear RGB to sRGB, written as EXR (linear) and PNG (tone-mapped)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image as mpimg
import numpy as np

from ..io.atomic import atomic_path
from ..mitsuba import mitsuba


def tonemap(img: np.ndarray, exposure: float) -> np.ndarray:
    """Linear RGB × exposure → sRGB in [0, 1] (clipped)."""
    x = np.clip(img * exposure, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def save_images(img: np.ndarray, stem: Path, exposure: float) -> tuple[Path, Path]:
    """``stem.exr`` (linear HDR, via Mitsuba's Bitmap/OpenEXR) and ``stem.png`` (tone-mapped), atomically."""
    mi = mitsuba()
    stem = Path(stem)
    exr, png = stem.with_suffix(".exr"), stem.with_suffix(".png")
    with atomic_path(exr) as tmp:
        mi.Bitmap(img.astype(np.float32)).write(str(tmp))
    with atomic_path(png) as tmp:
        mpimg.imsave(tmp, tonemap(img, exposure))
    return exr, png
