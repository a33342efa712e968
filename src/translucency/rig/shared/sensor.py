"""The virtual rigs' camera sensor: radiance → raw pixel values, with the noise and the defects a lab's has.

Raw value Z = clip(Poisson(k·L·vig·prnu / gain)·gain + dark + N(0, read²), saturation) for radiance L
(W mm⁻² sr⁻¹, per unit of the light's power or intensity): ``k`` values per unit radiance, ``gain``
values per electron (photon noise), ``read_noise`` in values, a dark offset with a gentle gradient, the
vignetting 1 + k1 ρ² + k2 ρ⁴ (ρ from the image centre in half-diagonals) and the pixels' response
non-uniformity (the flat field).  Both virtual rigs expose their renders with it
(:mod:`translucency.rig.planar.photographs`, :mod:`translucency.rig.object.photographs`); the importers
undo it with the calibration they are handed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Sensor:
    """Raw pixel value = clip(Poisson(k·L·vig·prnu / gain)·gain + dark + N(0, read²), saturation).

    ``k``: value per unit radiance; ``gain``: values per electron; ``vignetting``: (k1, k2) of
    1 + k1 ρ² + k2 ρ⁴ (ρ from the image centre in half-diagonals); ``prnu``: relative spread of the
    pixels' response (the flat field); ``dark``: mean dark offset (with a gentle gradient).

    Examples
    --------
    Without read noise, dark offset, vignetting or flat field, and with gain 0 (no photon noise), a raw
    value is k·L, clipped at saturation:

    >>> ideal = Sensor(k=10.0, gain=0.0, read_noise=0.0, dark=0.0, vignetting=(), prnu=0.0)
    >>> ideal.expose(np.array([[[1.0, 2.0, 10.0]]])).round(3).tolist()
    [[[10.0, 20.0, 60.0]]]

    The default sensor's flat field has mean 1; its vignetting is 1 at the image centre:

    >>> dark, flat, vig = Sensor().frames((5, 5, 3))
    >>> round(float(flat.mean()), 5), float(vig[2, 2, 0]), dark.shape
    (1.0, 1.0, (5, 5, 3))
    """

    k: float = 5e6
    gain: float = 0.01
    read_noise: float = 0.02
    dark: float = 0.5
    vignetting: tuple = (-0.3, 0.05)
    prnu: float = 0.02
    saturation: float = 60.0

    def frames(self, shape, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The dark frame, the flat field (mean 1) and the vignetting fall-off of this sensor."""
        rng = np.random.default_rng(seed)
        H, W = shape[:2]
        v, u = np.mgrid[0:H, 0:W].astype(np.float32)
        dark = self.dark * (1 + 0.2 * (u / W - 0.5))[..., None] * np.ones(3, np.float32)
        flat = 1 + self.prnu * rng.standard_normal((H, W, 3)).astype(np.float32)
        flat /= flat.mean()
        rho2 = ((u - (W - 1) / 2) ** 2 + (v - (H - 1) / 2) ** 2) / (0.25 * (W * W + H * H))
        vig = np.ones_like(rho2)
        for i, c in enumerate(self.vignetting, start=1):
            vig = vig + c * rho2**i
        return dark.astype(np.float32), flat.astype(np.float32), vig[..., None].astype(np.float32)

    def expose(self, radiance: np.ndarray, seed: int = 0, frames_seed: int = 0) -> np.ndarray:
        """Raw pixel values of one exposure of ``radiance``."""
        dark, flat, vig = self.frames(radiance.shape, frames_seed)
        rng = np.random.default_rng(seed)
        signal = np.maximum(self.k * radiance * vig * flat, 0.0)
        # shot noise in electrons, back in values; gain 0: a noise-free signal (no electrons to count)
        shot = rng.poisson(signal / self.gain) * self.gain if self.gain > 0 else signal
        raw = shot + dark + self.read_noise * rng.standard_normal(radiance.shape)
        return np.minimum(raw, self.saturation).astype(np.float32)
