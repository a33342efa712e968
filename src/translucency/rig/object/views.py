"""A camera's view of the object, prepared once per import (steps 1–2 of :mod:`.importer`).

A :class:`CameraView` holds a calibrated camera (:mod:`.cameras`), its surface map W (:mod:`.surface_map`)
and, at the pixels the map uses, the dark value and the gain k · vig(ρ) · flat: the raw value per unit
radiance per second (W mm⁻² sr⁻¹) of :mod:`.setup`'s radiometry, with vig(ρ) = 1 + k1 ρ² + k2 ρ⁴ and ρ
from the image centre in half-diagonals.  A mesh most of whose vertices project outside every image is
refused (:func:`check_mesh_seen`): it is not the object the cameras saw.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..._validate import TranslucencyError, plain
from ..shared.hdr import read_hdr
from .cameras import Camera
from .setup import CameraSetup, ObjectRig
from .surface_map import SurfaceMap, projects_inside, surface_map

#: the least fraction of the mesh's vertices that must project into some camera's image
MIN_PROJECTED = 0.5


@dataclass
class CameraView:
    """A calibrated camera with its map and its corrected frames (read once)."""

    camera: Camera
    map: SurfaceMap
    setup: CameraSetup
    dark_u: np.ndarray  # (n, 3) float32 raw value at the pixels the map uses
    gain_u: np.ndarray  # (n, 3) float32: k · vig · flat — raw value per unit radiance per second


def vignetting(width: int, height: int, coeffs) -> np.ndarray:
    """1 + k1 ρ² + k2 ρ⁴ + … with ρ from the image centre in half-diagonals (H·W,)."""
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    rho2 = ((u - (width - 1) / 2) ** 2 + (v - (height - 1) / 2) ** 2) / (0.25 * (width**2 + height**2))
    vig = np.ones_like(rho2)
    for i, c in enumerate(coeffs, start=1):
        vig += c * rho2**i
    return vig.ravel()


def read_frame(path: Path, shape, what: str) -> np.ndarray:
    """An HDR frame of the camera's ``shape`` (H, W) as its pixels (H·W, 3); ``what`` names it in errors."""
    image = read_hdr(path)
    if image.shape[:2] != shape:
        raise TranslucencyError(
            f"{path}: {what} is {image.shape[1]} x {image.shape[0]} px, the camera {shape[1]} x {shape[0]}"
        )
    if not np.isfinite(image).all():
        raise TranslucencyError(f"{path}: {what} holds non-finite pixels")
    return image.reshape(-1, 3)


def prepare_view(
    setup: CameraSetup, camera: Camera, rig: ObjectRig, mesh, scene, grazing_deg=None
) -> CameraView:
    """The view of camera ``setup`` posed as ``camera``: its map (pixels beyond ``grazing_deg``, default
    the rig's, left out), dark frame and gain at the pixels the map uses."""
    shape = (setup.height, setup.width)
    rad = setup.radiometry
    n_pix = shape[0] * shape[1]
    dark = read_frame(rad.dark, shape, "dark frame").astype(np.float64) if rad.dark else np.zeros((n_pix, 3))
    flat = read_frame(rad.flat, shape, "flat field").astype(np.float64) if rad.flat else np.ones((n_pix, 3))
    if (flat <= 0).any():
        raise TranslucencyError(f"{rad.flat}: flat field must be positive everywhere")
    flat = flat / flat.mean()  # normalised here: k is the response of a mean pixel
    vig = vignetting(setup.width, setup.height, rad.vignetting)
    if (vig <= 0).any():
        raise TranslucencyError(f"camera {setup.name}: vignetting {plain(rad.vignetting)} is not positive")
    gain = rad.k * vig[:, None] * flat
    m = surface_map(mesh, camera, grazing_deg=grazing_deg or rig.grazing_deg, scene=scene)
    return CameraView(camera, m, setup, dark[m.used].astype(np.float32), gain[m.used].astype(np.float32))


def check_mesh_seen(mesh, cameras: list[Camera], rig: ObjectRig) -> None:
    """Refuse a mesh that is not the one the cameras saw: most vertices outside every image."""
    fraction = float(np.logical_or.reduce([projects_inside(mesh, cam) for cam in cameras]).mean())
    if fraction < MIN_PROJECTED:
        raise TranslucencyError(
            f"{rig.mesh_file}: only {100 * fraction:.0f} % of the mesh's vertices project into any camera's "
            "image: is it the object the cameras saw (mesh.scale_mm, mesh.up, the poses)?"
        )
