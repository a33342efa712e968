"""Tone mapping and the picture files: linear RGB to sRGB, written as EXR (linear) and PNG (tone-mapped).

The exposure is the factor on the linear radiance (W/(mm² sr)) before the sRGB curve.  An
:class:`Exposure` chooses it:

* ``fixed`` (the default): from the object and the light's power alone — a diffuse surface of the
  object's total reflectance R facing the light at the reference distance (radiance R E / π) shows at
  :data:`FIXED_KEY` — so every picture of one object under lights of one power shares one exposure and
  can be compared by eye (``fixed+1`` / ``fixed-1``: a stop brighter / darker);
* ``auto``: per picture, the 99th percentile of the object's pixels at :data:`AUTO_KEY` (the reference's
  where there is one);
* a number: that factor itself (the ``exposure`` a summary states, to match another picture).

The EXR files hold the linear radiance, whatever the exposure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np

from .._validate import TranslucencyError
from ..io.atomic import atomic_path
from ..mitsuba import mitsuba

#: the display value (linear, before sRGB) of a diffuse surface of the object's reflectance facing the
#: light at the reference distance, under a fixed exposure (sRGB 0.74)
FIXED_KEY = 0.5
#: the display value (linear) of the 99th percentile of the object's pixels, under an auto exposure
AUTO_KEY = 0.8


def tonemap(img: np.ndarray, exposure: float) -> np.ndarray:
    """Linear RGB × exposure → sRGB in [0, 1] (clipped).

    Examples
    --------
    >>> tonemap(np.array([-1.0, 0.001, 0.25, 0.5, 2.0]), 1.0).round(4)  # linear toe, then 1.055 x^(1/2.4)
    array([0.    , 0.0129, 0.5371, 0.7354, 1.    ])
    >>> tonemap(np.array([0.25]), 2.0) == tonemap(np.array([0.5]), 1.0)  # the exposure scales the radiance
    array([ True])
    """
    x = np.clip(img * exposure, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def auto_exposure(image: np.ndarray, mask: np.ndarray) -> float:
    """The exposure that shows the 99th percentile of ``image`` over the pixels of ``mask`` at
    :data:`AUTO_KEY`."""
    return AUTO_KEY / max(float(np.quantile(image[mask], 0.99)), 1e-30)


@dataclass(frozen=True)
class Exposure:
    """How a picture is exposed: ``rule`` ``"fixed"`` (``stops`` brighter or darker), ``"auto"`` or
    ``"scale"`` (the factor ``scale`` itself); the module docstring states each.

    Examples
    --------
    >>> e = parse_exposure("fixed+1")
    >>> e.fixed(reflectance=0.5, irradiance=2.0 * np.pi)  # R E / π = 1 shows at 0.5, a stop brighter: 1
    1.0
    """

    rule: str = "fixed"
    stops: float = 0.0
    scale: float | None = None

    def fixed(self, *, reflectance: float, irradiance: float) -> float:
        """The fixed exposure of an object of total reflectance R under a light bringing ``irradiance``
        E (W/mm²) at the reference distance: FIXED_KEY / (R E / π), times 2^stops."""
        return FIXED_KEY / (reflectance * irradiance / math.pi) * 2.0**self.stops

    def describe(self, *, reflectance: float, irradiance: float, distance: float) -> str:
        """One sentence: how the fixed exposure was chosen."""
        stops = f", {self.stops:+g} stops" if self.stops else ""
        return (
            f"fixed{stops}: R E/pi shown at {FIXED_KEY:g} (linear), R = {reflectance:.4g} (the model's "
            f"median total reflectance x alpha), E = {irradiance:.4g} W/mm^2 (the light at "
            f"{distance:.4g} mm, the relative lights' default distance)"
        )


def parse_exposure(text: str, name: str = "exposure") -> Exposure:
    """``fixed``, ``fixed+STOPS``, ``fixed-STOPS``, ``auto`` or a factor > 0; ``name`` heads the message."""
    t = str(text).strip().lower()
    if t in ("fixed", "auto"):
        return Exposure(t)
    try:
        if t.startswith("fixed"):
            stops = float(t[5:])
            if math.isfinite(stops) and abs(stops) <= 64:
                return Exposure("fixed", stops=stops)
        else:
            scale = float(t)
            if math.isfinite(scale) and 0 < scale <= 1e30:
                return Exposure("scale", scale=scale)
    except ValueError:
        pass
    raise TranslucencyError(
        f"{name}: expected fixed, fixed+STOPS, fixed-STOPS (|STOPS| <= 64), auto or a factor in (0, 1e30], "
        f"got {text!r}"
    )


def save_images(img: np.ndarray, stem: Path, exposure: float) -> tuple[Path, Path]:
    """``stem.exr`` (linear HDR, via Mitsuba's Bitmap/OpenEXR) and ``stem.png`` (tone-mapped), atomically.

    Examples
    --------
    >>> import tempfile
    >>> from translucency.mitsuba import mitsuba
    >>> img = np.full((2, 3, 3), 0.5)
    >>> exr, png = save_images(img, Path(tempfile.mkdtemp()) / "picture", exposure=1.0)
    >>> exr.name, png.name
    ('picture.exr', 'picture.png')
    >>> back = np.asarray(mitsuba().Bitmap(str(exr)))  # the EXR: the linear radiance, whatever the exposure
    >>> back.shape, float(back.max())
    ((2, 3, 3), 0.5)
    >>> round(float(mpimg.imread(png)[0, 0, 0]) * 255)  # the PNG: sRGB of 0.5 in 8 bits (0.7354 × 255)
    187
    """
    mi = mitsuba()
    stem = Path(stem)
    exr, png = stem.with_suffix(".exr"), stem.with_suffix(".png")
    with atomic_path(exr) as tmp:
        mi.Bitmap(img.astype(np.float32)).write(str(tmp))
    with atomic_path(png) as tmp:
        mpimg.imsave(tmp, tonemap(img, exposure))
    return exr, png
