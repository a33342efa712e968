"""What both importers and both virtual rigs share: HDR frames, the plane-to-image homography, checkerboards,
the virtual sensor.

:mod:`.hdr` reads OpenEXR / Radiance HDR / PFM, writes PFM and EXR, and merges bracketed LDR exposures;
:mod:`.homography` holds the plane-to-image homography and the pixel conventions of ``rig/``;
:mod:`.checkerboard` finds a checkerboard's corners (OpenCV) and the homography they fix; :mod:`.sensor`
is the virtual rigs' camera sensor (radiance → raw values with noise, dark frame, flat field, vignetting)
and :mod:`.spot` their laser's power.
"""

from .checkerboard import find_corners, homography_from_checkerboard
from .hdr import merge_exposures, read_hdr, read_pfm, write_exr, write_hdr, write_pfm
from .homography import Homography, homography_from_points
from .sensor import Sensor
from .spot import spot_power

__all__ = [
    "Homography",
    "Sensor",
    "find_corners",
    "homography_from_checkerboard",
    "homography_from_points",
    "merge_exposures",
    "read_hdr",
    "read_pfm",
    "spot_power",
    "write_exr",
    "write_hdr",
    "write_pfm",
]
