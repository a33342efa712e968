"""The generated example files: a small sky (``sky.exr``) and a user's filling (``filling.npz``).

Regenerate them, the same bytes of arrays each time::

    python -m translucency.data.make_examples [FOLDER]

(default: the package's ``data/examples``).  The meshes (``spot.obj``, ``cow.obj``) are copies of public
models and ``scene.xml`` is written by hand; ``LICENSES.md`` beside them says where each file comes from.

``sky.exr``
    A latitude–longitude sky of :data:`SKY_SIZE` pixels in linear RGB, W/(mm² sr) as the ``env:`` light
    reads it: a blue gradient from the horizon (whiter) to the zenith, a warm sun-like lobe
    :data:`SUN_ELEVATION_DEG` above the horizon, and a dim ground below.  Mitsuba's ``envmap`` layout (row 0
    at the map's +Y, turned to the scene's +Z by the ``env:`` light and by ``scene.xml``).
``filling.npz``
    A block of marble with green-grey veins, :data:`FILLING_VOXELS` voxels of :data:`FILLING_VOXEL_MM` mm
    (a :data:`FILLING_SIZE_MM` mm cube, enough for ``spot.obj`` and ``cow.obj``, about 100 mm each):
    ``sigma_s``, ``sigma_a`` (Z, Y, X, 3) in mm⁻¹, ``voxel_mm``, ``g`` and ``eta``, as
    ``acquire planar --volume`` and ``acquire mesh --volume`` read them
    (:func:`translucency.acquire.load_volume`).
``spot_coarse.model.zip``, the small fitted object, is made by the library's own acquisition and fit:
:mod:`translucency.workflow.examples` (``python -m translucency.workflow.examples [FOLDER]``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_path
from ..mitsuba import mitsuba

#: the sky's (width, height) in pixels: 5.6 degrees a pixel
SKY_SIZE = (64, 32)
#: the sun's elevation above the horizon and its azimuth (degrees from +y towards +x: front right of
#: scene.xml's camera, on +y looking at −y)
SUN_ELEVATION_DEG, SUN_AZIMUTH_DEG = 45.0, 330.0
#: the filling's voxels per axis and their size (mm)
FILLING_VOXELS, FILLING_VOXEL_MM = 27, 4.0
FILLING_SIZE_MM = FILLING_VOXELS * FILLING_VOXEL_MM
#: marble (Jensen et al. 2001, σ_s' and σ_a in mm⁻¹, taken as σ_s with g = 0) and the veins' absorption
MARBLE_SIGMA_S = (2.19, 2.62, 3.00)
MARBLE_SIGMA_A = (0.0021, 0.0041, 0.0071)
VEIN_SIGMA_A = (0.060, 0.030, 0.050)


def sky_directions(width: int, height: int) -> np.ndarray:
    """(height, width, 3) unit directions of the pixel centres of a latitude–longitude map in the scene's
    frame (+Z up), as Mitsuba's ``envmap`` turned by 90° about x reads them.

    Examples
    --------
    >>> d = sky_directions(4, 2)
    >>> bool(np.allclose(np.linalg.norm(d, axis=-1), 1.0)), bool((d[0, :, 2] > 0).all())  # row 0: the sky
    (True, True)
    """
    theta = (np.arange(height) + 0.5) / height * np.pi  # from the zenith
    phi = (np.arange(width) + 0.5) / width * 2.0 * np.pi  # from +y towards +x
    t, p = np.meshgrid(theta, phi, indexing="ij")
    return np.stack([np.sin(p) * np.sin(t), np.cos(p) * np.sin(t), np.cos(t)], axis=-1)


def sky(width: int = SKY_SIZE[0], height: int = SKY_SIZE[1]) -> np.ndarray:
    """The example sky: (height, width, 3) linear RGB radiance, W/(mm² sr).

    Examples
    --------
    >>> s = sky()
    >>> s.shape, s.dtype, bool(s.min() > 0)
    ((32, 64, 3), dtype('float32'), True)
    >>> row, col = np.unravel_index(np.argmax(s.sum(axis=-1)), s.shape[:2])
    >>> bool(sky_directions(64, 32)[row, col, 2] > 0.5)   # the brightest pixel: the sun, high in the sky
    True
    """
    d = sky_directions(width, height)
    up = np.clip(d[..., 2], 0.0, 1.0)[..., None]
    # the sky: whiter at the horizon, deeper blue towards the zenith; below the horizon a dim ground
    horizon, zenith = np.array([0.30, 0.33, 0.38]), np.array([0.08, 0.15, 0.32])
    out = np.where(d[..., 2:3] > 0, horizon + (zenith - horizon) * np.sqrt(up), [0.05, 0.045, 0.04])
    # the sun: a narrow bright lobe with a wider aureole, warm
    e, a = np.radians(SUN_ELEVATION_DEG), np.radians(SUN_AZIMUTH_DEG)
    sun = np.array([np.sin(a) * np.cos(e), np.cos(a) * np.cos(e), np.sin(e)])
    angle = np.arccos(np.clip(d @ sun, -1.0, 1.0))
    lobe = 30.0 * np.exp(-0.5 * (angle / np.radians(4.0)) ** 2) + 1.5 * np.exp(-0.5 * (angle / 0.25) ** 2)
    out = out + lobe[..., None] * np.array([1.0, 0.92, 0.80])
    return out.astype(np.float32)


def filling(seed: int = 7) -> dict:
    """The example filling: a marble block with veins, the arrays of ``filling.npz``.

    Examples
    --------
    >>> f = filling()
    >>> f["sigma_s"].shape, float(f["voxel_mm"]), FILLING_SIZE_MM
    ((27, 27, 27, 3), 4.0, 108.0)
    >>> bool((f["sigma_a"] >= np.array(MARBLE_SIGMA_A, np.float32)).all())   # veins only add absorption
    True
    """
    rng = np.random.default_rng(seed)
    n, h = FILLING_VOXELS, FILLING_VOXEL_MM
    c = (np.arange(n) + 0.5) * h  # voxel centres, mm
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    # a smooth turbulence: a few random plane waves of 20-60 mm
    turb = np.zeros_like(x)
    for _ in range(6):
        k = rng.normal(size=3)
        k *= 2 * np.pi / (np.linalg.norm(k) * rng.uniform(20.0, 60.0))
        turb += np.sin(k[0] * x + k[1] * y + k[2] * z + rng.uniform(0, 2 * np.pi))
    # the veins: thin sheets where a slanted wave crosses zero, bent by the turbulence
    vein = np.exp(-0.5 * (np.sin(2 * np.pi * (x + 0.6 * z + 6.0 * turb) / 36.0) / 0.18) ** 2)
    w = vein[..., None]
    sigma_s = np.asarray(MARBLE_SIGMA_S) * (1.0 - 0.3 * w)
    sigma_a = np.asarray(MARBLE_SIGMA_A) + w * np.asarray(VEIN_SIGMA_A)
    return {
        "sigma_s": sigma_s.astype(np.float32),
        "sigma_a": sigma_a.astype(np.float32),
        "voxel_mm": np.float64(h),
        "g": np.float64(0.0),
        "eta": np.float64(1.3),
    }


def write_examples(folder) -> list[Path]:
    """Write ``sky.exr`` and ``filling.npz`` into ``folder`` (atomically); returns their paths."""
    folder = Path(folder)
    with atomic_path(folder / "sky.exr") as tmp:
        mitsuba().Bitmap(sky()).write(str(tmp))
    with atomic_path(folder / "filling.npz") as tmp:
        np.savez_compressed(tmp, **filling())
    return [folder / "sky.exr", folder / "filling.npz"]


if __name__ == "__main__":  # pragma: no cover
    for written in write_examples(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "examples"):
        print(written, written.stat().st_size, "bytes")
