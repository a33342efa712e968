"""A real rig's data: HDR photographs of a scanned laser spot, with camera calibration, as planar data sets.

:mod:`.hdr` reads OpenEXR / Radiance HDR / PFM and merges bracketed LDR exposures; :mod:`.calibration`
holds the plane-to-image homography (matrix, marked points, checkerboard) and the radiometric corrections;
:mod:`.importer` turns the images into a planar data set (``translucency import images``) through
:mod:`.positions` (the table of laser positions), :mod:`.frames` (reading and correcting an image),
:mod:`.resample` (onto the sample plane), :mod:`.beam` (the beam-width correction) and
:mod:`.provenance` (hashes and header), with its arguments in :mod:`.setup`;
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
from .importer import import_images
from .positions import Shot, read_positions
from .setup import ImportSetup

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
