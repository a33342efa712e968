"""A real rig's photographs → data sets: two importers, each with its virtual rig, on one contract.

* **The planar importer** (:mod:`.planar`, ``translucency import images``, :func:`import_images`): HDR
  photographs of a laser spot scanned over a flat sample, with the camera's plane-to-image homography and
  radiometric calibration → a planar data set, as ``acquire planar`` writes it
  (docs/reference/planar-rig.md).  Its
  virtual rig, :mod:`.planar.photographs` (:func:`photograph_sample`), renders a virtual DISCO sample
  with Mitsuba 3 and writes what a lab would hand over.
* **The object importer** (:mod:`.object`, ``translucency import object``, :func:`import_object`):
  multi-view HDR photographs of a laser stepped over a scanned mesh, with calibrated cameras
  (``object.json``, :func:`read_object_rig`) → a mesh data set, as ``acquire mesh`` writes it
  (docs/reference/object-rig.md).  Its virtual rig, :mod:`.object.photographs` (:func:`photograph_object`),
  renders a filled mesh lit by a laser from cameras around it.

The layout: :mod:`.contract` is what both importers are — a setup read and checked, chunks of laser
shots, a data set written chunk by chunk and resumed (:class:`Importer`, :func:`run_import`);
:mod:`.shared` holds what both use (HDR frames, the homography and its pixel conventions, checkerboards,
the virtual rigs' sensor and laser power); each importer's folder holds its steps, one concept a module,
and its virtual rig beside it.
"""

from .contract import Chunk, Importer, run_import
from .object import LaserBeam, ObjectImport, ObjectRig, import_object, photograph_object, read_object_rig
from .planar import (
    Beam,
    Calibration,
    ImportSetup,
    PlanarImport,
    Shot,
    VirtualCamera,
    import_images,
    load_calibration,
    photograph_sample,
    read_positions,
    scale_from_reference,
)
from .shared import (
    Homography,
    Sensor,
    homography_from_checkerboard,
    homography_from_points,
    merge_exposures,
    read_hdr,
    read_pfm,
    write_pfm,
)

__all__ = [
    # the contract
    "Chunk",
    "Importer",
    "run_import",
    # shared
    "Homography",
    "Sensor",
    "homography_from_points",
    "homography_from_checkerboard",
    "merge_exposures",
    "read_hdr",
    "read_pfm",
    "write_pfm",
    # the planar importer and its virtual rig
    "Calibration",
    "ImportSetup",
    "PlanarImport",
    "Shot",
    "import_images",
    "load_calibration",
    "read_positions",
    "scale_from_reference",
    "Beam",
    "VirtualCamera",
    "photograph_sample",
    # the object importer and its virtual rig
    "ObjectImport",
    "ObjectRig",
    "import_object",
    "read_object_rig",
    "LaserBeam",
    "photograph_object",
]
