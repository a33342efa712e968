"""A real rig's data: HDR photographs of a scanned laser spot, with camera calibration, as planar data sets.

:mod:`.hdr` reads OpenEXR / Radiance HDR / PFM and merges bracketed LDR exposures; :mod:`.calibration`
holds the plane-to-image homography (matrix, marked points, checkerboard) and the radiometric corrections;
:mod:`.importer` turns the images into a planar data set (``translucency import images``);
:mod:`.photographs` renders virtual photographs of a virtual DISCO sample with Mitsuba 3, the test rig.
"""

from .calibration import (
    Calibration,
    Homography,
    homography_from_checkerboard,
    homography_from_points,
    load_calibration,
    scale_from_reference,
)
from .hdr import merge_exposures, read_hdr, read_pfm, write_pfm
from .importer import ImportSetup, Shot, import_images, read_positions

__all__ = [
    "Calibration",
    "Homography",
    "homography_from_points",
    "homography_from_checkerboard",
    "load_calibration",
    "scale_from_reference",
    "merge_exposures",
    "read_hdr",
    "read_pfm",
    "write_pfm",
    "ImportSetup",
    "Shot",
    "import_images",
    "read_positions",
]
