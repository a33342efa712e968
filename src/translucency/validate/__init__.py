"""Validation harnesses: our photon tally cross-checked against independent references.

A slab is lit by a narrow spot (:mod:`.beam`) and seen through a window of pixels (:mod:`.window`);
:mod:`.volpath` renders it with Mitsuba 3's own ``volpath``, :mod:`.tally` estimates the same radiance
image from our photon walk, and :mod:`.statistics` compares the two (per-pixel z-scores, ring profiles).
The Mitsuba scenes are built in :mod:`translucency.mitsuba.scenes`.
"""

from ..mitsuba import NO_ROULETTE
from .beam import SpotBeam, sample_spot_entries, spot_irradiance, spot_power, spot_profile
from .statistics import Agreement, compare, ring_profile, z_scores
from .tally import WALK_BATCH, TopExits, pixel_index, radiance_from_exits, tally_radiance, walk_spot
from .volpath import render_volpath_spot, volpath_scene
from .window import CAMERA_HEIGHT_MM, PixelWindow, RadianceImage, pixel_centres

__all__ = [
    "SpotBeam",
    "PixelWindow",
    "pixel_centres",
    "spot_irradiance",
    "spot_profile",
    "spot_power",
    "sample_spot_entries",
    "RadianceImage",
    "volpath_scene",
    "render_volpath_spot",
    "TopExits",
    "walk_spot",
    "pixel_index",
    "radiance_from_exits",
    "tally_radiance",
    "z_scores",
    "ring_profile",
    "Agreement",
    "compare",
    "CAMERA_HEIGHT_MM",
    "NO_ROULETTE",
    "WALK_BATCH",
]
