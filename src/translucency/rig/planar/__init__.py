"""The planar importer: HDR photographs of a laser spot scanned over a flat sample → a planar data set.

:mod:`.importer` (``translucency import images``, :func:`import_images`) runs the import's chunks through
:mod:`.positions` (the table of laser positions), :mod:`.frames` (reading and correcting an image),
:mod:`.resample` (onto the sample plane), :mod:`.beam` (the beam-width correction) and :mod:`.provenance`
(hashes and header), with its arguments in :mod:`.setup` and the camera's homography and radiometric
corrections in :mod:`.calibration`; :mod:`.photographs` is its virtual rig: Mitsuba 3 photographs of a
virtual DISCO sample, the importer's test rig.
"""

from .calibration import Calibration, load_calibration, scale_from_reference
from .importer import PlanarImport, import_images
from .photographs import Beam, VirtualCamera, photograph_sample
from .positions import Shot, read_positions
from .setup import ImportSetup

__all__ = [
    "Beam",
    "Calibration",
    "ImportSetup",
    "PlanarImport",
    "Shot",
    "VirtualCamera",
    "import_images",
    "load_calibration",
    "photograph_sample",
    "read_positions",
    "scale_from_reference",
]
