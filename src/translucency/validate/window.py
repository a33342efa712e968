"""The window the validation looks at: an orthographic camera's square of pixels on the slab's top face,
and the radiance image over it that both estimates produce.

The camera is ``orthographic`` along −z with an ``hdrfilm`` and a box filter, so a pixel's value is the
mean radiance :math:`L(\\vec x_o, +\\hat z)` over its footprint.  Units: mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError
from ..acquire.volume import Volume
from ..mitsuba import load_plugin, mitsuba
from ._checks import check_point, check_positive
from .beam import SpotBeam

CAMERA_HEIGHT_MM = 10.0  # orthographic camera plane above the slab (any height > 0 would do)


@dataclass(frozen=True)
class PixelWindow:
    """A square window of ``n_pixels`` × ``n_pixels`` pixels of side ``pitch_mm`` centred on ``centre_xy``.

    Examples
    --------
    >>> w = PixelWindow((2.0, 2.0), n_pixels=4, pitch_mm=0.5)
    >>> w.side_mm, w.sensor_dict()["type"], w.sensor_dict()["film"]["width"]
    (2.0, 'orthographic', 4)
    """

    centre_xy: tuple[float, float]
    n_pixels: int = 16
    pitch_mm: float = 0.25

    def __post_init__(self):
        object.__setattr__(self, "centre_xy", check_point("window centre", self.centre_xy))
        n = check_positive("window pixels", self.n_pixels, "pixels")
        if n != int(n):
            raise TranslucencyError(f"window pixels: must be a positive integer, got {self.n_pixels!r}")
        object.__setattr__(self, "n_pixels", int(n))
        object.__setattr__(self, "pitch_mm", check_positive("pitch", self.pitch_mm))

    @property
    def side_mm(self) -> float:
        return self.n_pixels * self.pitch_mm

    def sensor_dict(self, spp: int = 1) -> dict:
        """Mitsuba ``orthographic`` sensor looking down −z at this window (box filter, RGB film)."""
        mi = mitsuba()
        cx, cy = self.centre_xy
        half = 0.5 * self.side_mm  # the orthographic camera sees [-1, 1]² in its local frame
        to_world = (
            mi.ScalarTransform4f().translate([cx, cy, CAMERA_HEIGHT_MM])
            @ mi.ScalarTransform4f().scale([half, half, 1.0])
            @ mi.ScalarTransform4f().look_at(origin=[0, 0, 0], target=[0, 0, -1], up=[0, 1, 0])
        )
        return {
            "type": "orthographic",
            "to_world": to_world,
            "film": {
                "type": "hdrfilm",
                "width": self.n_pixels,
                "height": self.n_pixels,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": "independent", "sample_count": int(spp)},
        }


def pixel_centres(window: PixelWindow) -> tuple[np.ndarray, np.ndarray]:
    """Centres (x, y) in mm of the window's pixels, shape (n, n) each, indexed [row, column].

    Read from Mitsuba itself: the ray its sensor traces through each pixel
    centre, so the mapping of image rows and columns to the slab does not rest
    on our reading of the orthographic transform.

    Examples
    --------
    >>> x, y = pixel_centres(PixelWindow((2.0, 2.0), n_pixels=4, pitch_mm=0.5))
    >>> x[0].round(4).tolist(), y[:, 0].round(4).tolist()   # columns run along +x, rows down along −y
    ([1.25, 1.75, 2.25, 2.75], [2.75, 2.25, 1.75, 1.25])
    """
    mi = mitsuba()
    n = window.n_pixels
    sensor = load_plugin(window.sensor_dict())
    col, row = np.meshgrid(np.arange(n), np.arange(n))
    u = ((col + 0.5) / n).ravel().astype(np.float32)
    v = ((row + 0.5) / n).ravel().astype(np.float32)
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(u, v), mi.Point2f(0.5, 0.5))
    x = np.asarray(ray.o.x, dtype=np.float64).reshape(n, n)
    y = np.asarray(ray.o.y, dtype=np.float64).reshape(n, n)
    return x, y


@dataclass
class RadianceImage:
    """Radiance L(x_o, +z) leaving the top face, per pixel, per unit intensity of the spot.

    ``radiance`` and ``variance`` (of the estimate) have shape (n, n, C) for the
    C rendered ``channels``; ``x``, ``y`` (n, n) are the pixel centres (mm);
    ``seconds`` is the wall time of the estimate (per channel in ``seconds_per_channel``).

    Examples
    --------
    >>> x, y = np.meshgrid([0.5, 1.5], [1.5, 0.5])
    >>> image = RadianceImage(np.ones((2, 2, 1)), np.zeros((2, 2, 1)), x, y, channels=(1,), seconds=0.0)
    >>> image.radiance.shape, image.channels   # (n, n, C): one rendered channel, green
    ((2, 2, 1), (1,))
    """

    radiance: np.ndarray
    variance: np.ndarray
    x: np.ndarray
    y: np.ndarray
    channels: tuple[int, ...]
    seconds: float
    seconds_per_channel: tuple[float, ...] = ()


def _check_fits(volume: Volume, beam: SpotBeam, window: PixelWindow) -> None:
    """Beam and window must lie on the top face."""
    W, H, _ = volume.size_mm
    bx, by = beam.centre_xy
    r = beam.radius_mm
    if not (r <= bx <= W - r and r <= by <= H - r):
        raise TranslucencyError(
            f"beam: the lit disc at {beam.centre_xy} mm of radius {r:g} mm does not fit on the "
            f"{W:g} x {H:g} mm top face"
        )
    cx, cy = window.centre_xy
    h = 0.5 * window.side_mm
    if not (h <= cx <= W - h and h <= cy <= H - h):
        raise TranslucencyError(
            f"window: {window.side_mm:g} mm around {window.centre_xy} mm does not fit on the "
            f"{W:g} x {H:g} mm top face"
        )
