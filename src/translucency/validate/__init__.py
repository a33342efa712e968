"""Validation harnesses: our photon tally cross-checked against independent references.

:mod:`.volpath` renders a slab with Mitsuba 3's own ``volpath`` under a spot
light and estimates the same radiance image from the photon walk, then
compares the two (per-pixel z-scores, ring profiles).  The Mitsuba scene
builders it uses live in :mod:`translucency.mitsuba`.
"""

from .volpath import (
    CAMERA_HEIGHT_MM,
    NO_ROULETTE,
    WALK_BATCH,
    Agreement,
    PixelWindow,
    RadianceImage,
    SpotBeam,
    TopExits,
    compare,
    pixel_centres,
    pixel_index,
    radiance_from_exits,
    render_volpath_spot,
    ring_profile,
    sample_spot_entries,
    spot_irradiance,
    spot_power,
    spot_profile,
    tally_radiance,
    volpath_scene,
    walk_spot,
    z_scores,
)

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
