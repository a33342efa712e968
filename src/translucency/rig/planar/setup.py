"""The arguments of an import of photographs: output grid, window, masks, beam, chunking (lengths in mm)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._validate import TranslucencyError


@dataclass(frozen=True)
class ImportSetup:
    """Arguments of an import (lengths in mm).

    ``pitch``: output pixel; ``window``: window side (odd number of pixels, x_i in the centre one);
    ``supersample``: points per output pixel side (at least, raised to one per image pixel);
    ``specular_radius``: mask around x_i; ``dilate``:
    growth of the saturated mask, image pixels; ``floor``: values below it (after the dark frame) are
    under-exposed; ``sample_size``: (W, H) of the sample, pixels outside are masked (optional).

    Examples
    --------
    A window has an odd number of pixels, x_i in the centre one:

    >>> [ImportSetup(pitch=p, window=w).window_pixels() for p, w in ((0.25, 8.0), (0.5, 2.5))]
    [33, 5]
    >>> try:
    ...     ImportSetup(pitch=0.5, window=0.2).check()
    ... except TranslucencyError as exc:
    ...     print(exc)
    window: must be at least one pixel (0.5 mm), got 0.2
    """

    pitch: float = 0.25
    window: float = 8.0
    supersample: int = 3
    specular_radius: float = 0.0
    dilate: int = 1
    floor: float | None = None
    sample_size: tuple[float, float] | None = None
    eta: float = 1.3
    chunk_points: int = 16
    dtype: str = "float32"
    beam_rms: float = 0.0  # √⟨ρ²⟩ of the beam's irradiance on the sample, mm: 0 = a pencil beam

    def check(self) -> None:
        if not (np.isfinite(self.pitch) and self.pitch > 0):
            raise TranslucencyError(f"pitch: must be a positive length in mm, got {self.pitch}")
        if not (np.isfinite(self.window) and self.window >= self.pitch):
            raise TranslucencyError(
                f"window: must be at least one pixel ({self.pitch} mm), got {self.window}"
            )
        if not 1 <= int(self.supersample) <= 16:
            raise TranslucencyError(f"supersample: must lie in 1..16, got {self.supersample}")
        if not self.specular_radius >= 0 or not self.dilate >= 0:
            raise TranslucencyError("specular radius and dilate: must be >= 0")
        if self.chunk_points < 1:
            raise TranslucencyError(f"chunk: must be >= 1, got {self.chunk_points}")
        if not (np.isfinite(self.beam_rms) and self.beam_rms >= 0):
            raise TranslucencyError(f"beam rms: must be a length >= 0 mm, got {self.beam_rms}")
        if self.dtype not in ("float32", "float16"):
            raise TranslucencyError(f"dtype: expected float32 or float16, got {self.dtype!r}")

    def window_pixels(self) -> int:
        n = max(1, int(round(self.window / self.pitch)))
        return n if n % 2 == 1 else n + 1
