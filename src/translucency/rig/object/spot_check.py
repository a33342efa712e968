"""Poses checked by the data (a step of :mod:`.importer`): each shot's laser spot, found in the photographs
of every camera that sees its hit, against the pixel where the camera's pose projects the hit.

A wrong pose — R transposed, t's sign swapped, another camera's pose — can pass every check of the geometry
alone (most of the mesh still projects into the image); the spot cannot: with the right pose the brightest
point of a shot lies within about a pixel of the projected hit, with R transposed tens of pixels away.

The spot in a frame: the centroid of the pixels within :data:`PEAK_FRACTION` of the frame's brightest
luminance (a clipped peak is a plateau; its centroid is still the spot), in OpenCV's pixel coordinates
(pixel centres at integers, :meth:`~.cameras.Camera.project`).  A camera sees a hit when the hit lies in
front of it, inside its image, and the ray from its centre reaches the hit unblocked.  Units: pixels, mm.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from ..._validate import TranslucencyError
from ...mitsuba import rays
from .cameras import Camera
from .setup import ObjectRig
from .views import read_frame

#: the largest median distance (px) between a camera's laser spots and the hits its pose projects
MAX_SPOT_MISS_PX = 3.0
#: the pixels that make the spot: within this fraction of the frame's brightest luminance
PEAK_FRACTION = 0.9
#: a spot counts where the frame's brightest stands this many read-noise deviations above the dark
SPOT_SNR = 20.0
#: the shots whose spots check a camera's pose: the first this many that it sees (each read once)
SHOTS_CHECKED = 4


def spot_pixel(image: np.ndarray, noise: float = 0.0) -> np.ndarray | None:
    """The laser spot of a frame (H, W, 3), its dark frame taken off: the centroid (u, v) of its pixels
    within :data:`PEAK_FRACTION` of the brightest luminance, px; None where the brightest stands less than
    :data:`SPOT_SNR` times the read ``noise`` above zero (no spot to find: that shot does not check the pose).

    Examples
    --------
    >>> image = np.zeros((20, 30, 3), np.float32)
    >>> image[5, 12] = image[5, 13] = 100.0  # a peak clipped over two pixels
    >>> image[15, 3] = 50.0  # a fainter glow elsewhere
    >>> spot_pixel(image).tolist()
    [12.5, 5.0]
    """
    luminance = np.asarray(image, dtype=np.float64).mean(axis=2)
    if luminance.max() <= SPOT_SNR * noise:
        return None
    v, u = np.nonzero(luminance >= PEAK_FRACTION * luminance.max())
    return np.array([u.mean(), v.mean()])


def sees(camera: Camera, point: np.ndarray, scene) -> bool:
    """Whether ``camera`` sees the surface ``point`` (mm): in front, inside its image, unblocked."""
    point = np.asarray(point, dtype=np.float64)
    if camera.depth(point[None])[0] <= 0:
        return False
    u, v = camera.project(point[None])[0]
    if not (0 <= u <= camera.width - 1 and 0 <= v <= camera.height - 1):
        return False
    to = point - camera.centre
    distance = float(np.linalg.norm(to))
    # stop short of the surface (1e-3 of the way): the point's own face is not in the way
    blocked = scene.ray_test(rays(camera.centre[None], (to / distance)[None], np.array([0.999 * distance])))
    return not bool(np.asarray(blocked)[0])


def check_spots(rig: ObjectRig, cameras: list[Camera], hits: np.ndarray, scene) -> dict[str, float]:
    """Each camera's median distance (px) from its laser spots to the hits its pose projects; one line
    refusing a camera whose spots miss by more than :data:`MAX_SPOT_MISS_PX` (and saying when R transposed,
    or t's sign swapped, would fit them).  A camera that sees no hit is not in the result.

    Parameters
    ----------
    rig : ObjectRig
        The rig file read (its shots' frames and each camera's pose as given).
    cameras : list of Camera
        The cameras posed (in the rig's order).
    hits : array_like, shape (P, 3)
        Where each shot enters the surface, mm.
    scene : mitsuba.Scene
        The mesh, for the rays that tell whether a camera sees a hit.

    Returns
    -------
    dict of str to float
        Camera name → median spot miss, px.
    """
    misses = {}
    for setup, camera in zip(rig.cameras, cameras):
        spots = _Spots(rig, setup, hits, scene)
        miss = spots.miss(camera)
        if miss is None or miss > MAX_SPOT_MISS_PX:
            _refuse_if_wrong(rig, setup, camera, spots, miss)
        if miss is not None:
            misses[camera.name] = round(miss, 3)
    return misses


class _Spots:
    """One camera's laser spots, each shot's read once, and how far a pose puts the hits from them."""

    def __init__(self, rig: ObjectRig, setup, hits: np.ndarray, scene):
        self.rig, self.setup, self.hits, self.scene = rig, setup, hits, scene
        self.found: dict[int, np.ndarray | None] = {}

    def spot(self, j: int) -> np.ndarray | None:
        """The spot of shot ``j`` in the camera's longest exposure, or None without a frame or a spot."""
        if j not in self.found:
            frames = self.rig.shots[j].frames.get(self.setup.name, [])
            image = None
            if frames:
                frame = max(frames, key=lambda f: f.exposure_s)
                shape = (self.setup.height, self.setup.width)
                image = read_frame(frame.file, shape, "photograph").reshape(*shape, 3)
            noise = float(self.setup.radiometry.read_noise)
            self.found[j] = None if image is None else spot_pixel(image - self.dark, noise)
        return self.found[j]

    @cached_property
    def dark(self) -> np.ndarray:
        """The camera's dark frame (H, W, 3), 0 without one: a faint spot over a dark frame's fixed
        pattern is found after it is taken off."""
        rad, shape = self.setup.radiometry, (self.setup.height, self.setup.width)
        return (
            read_frame(rad.dark, shape, "dark frame").reshape(*shape, 3)
            if rad.dark
            else np.zeros((*shape, 3))
        )

    def shots(self, camera: Camera) -> list[int]:
        """The first :data:`SHOTS_CHECKED` shots whose hit ``camera`` sees and that it photographed."""
        seen = [j for j in range(len(self.hits)) if sees(camera, self.hits[j], self.scene)]
        return [j for j in seen if self.spot(j) is not None][:SHOTS_CHECKED]

    def miss(self, camera: Camera) -> float | None:
        """The median distance (px) from the spots to the hits ``camera`` projects; None: it sees none."""
        shots = self.shots(camera)
        if not shots:
            return None
        projected = camera.project(self.hits[shots])
        found = np.array([self.spot(j) for j in shots])
        return float(np.median(np.linalg.norm(projected - found, axis=1)))


def _refuse_if_wrong(rig: ObjectRig, setup, camera: Camera, spots: _Spots, miss: float | None) -> None:
    """One line refusing ``camera``'s pose where its spots miss the hits (or where it sees no hit but a
    usual slip of a pose given as R, t would fit them): the miss, and the slip that fits."""
    if "R" in setup.pose:  # a pose given as R, t: the usual slips
        for what, other in (
            ("R transposed", camera.with_pose(camera.R.T, camera.t)),
            ("t's sign swapped", camera.with_pose(camera.R, -camera.t)),
        ):
            fit = spots.miss(other)
            if fit is not None and fit <= MAX_SPOT_MISS_PX:
                where = (
                    "sees none of the hits"
                    if miss is None
                    else f"puts its laser spots {miss:.1f} px from the hits it projects"
                )
                raise TranslucencyError(
                    f"{rig.path}: camera {camera.name}: its pose {where} (at most {MAX_SPOT_MISS_PX:g} px); "
                    f"with {what} the spots lie {fit:.1f} px from them: a wrong pose"
                )
    if miss is not None:
        raise TranslucencyError(
            f"{rig.path}: camera {camera.name}: its pose puts its laser spots {miss:.1f} px from the hits "
            f"it projects (median of {len(spots.shots(camera))} shots; at most {MAX_SPOT_MISS_PX:g} px): a "
            "wrong pose — another camera's, or one of another object frame?"
        )


__all__ = ["MAX_SPOT_MISS_PX", "check_spots", "sees", "spot_pixel"]
