"""The object importer: multi-view HDR photographs of a laser stepped over a scanned mesh → a mesh data set.

:mod:`.importer` (``translucency import object``, :func:`import_object`) reads its setup in :mod:`.setup`
(``object.json``; the cameras of :mod:`.cameras`, OpenCV's model), prepares each camera's view once
(:mod:`.views`, with its visibility map :mod:`.surface_map`), snaps the laser hits (:mod:`.hits`), and per
shot turns the frames into radiance and cell means (:mod:`.radiance`), radiance into exitance by the exit
law (:mod:`.exit_law`, or estimated from the views: :mod:`.law_estimate`), fuses the cameras
(:mod:`.fusion`) and fills the unseen cells (:mod:`.fill`).  :mod:`.photographs` is its virtual rig:
Mitsuba 3 photographs of a filled mesh, with the checkerboards of :mod:`.targets` for the intrinsics.
"""

from .cameras import Camera
from .exit_law import Dielectric, ExitLaw, FromViews, Lambertian
from .fusion import GRAZING, SATURATED, SPOT, UNSEEN
from .importer import ObjectImport, import_object
from .photographs import LaserBeam, photograph_object
from .setup import ObjectRig, read_object_rig

__all__ = [
    "Camera",
    "Dielectric",
    "ExitLaw",
    "FromViews",
    "GRAZING",
    "LaserBeam",
    "Lambertian",
    "ObjectImport",
    "ObjectRig",
    "SATURATED",
    "SPOT",
    "UNSEEN",
    "import_object",
    "photograph_object",
    "read_object_rig",
]
