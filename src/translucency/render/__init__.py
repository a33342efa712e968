"""Rendering fitted objects, one stage walked down once.

:mod:`.object` (mesh, volume and boundary of a model) → :mod:`.lights` (one protocol, :class:`Light`) →
the prepared object (:mod:`translucency.transport`: the transport every renderer draws) → :mod:`.camera` →
:mod:`.picture` (our picture from the radiance per vertex) → :mod:`.tonemap` (sRGB, the files) →
:mod:`.reference` (the ``volpath`` reference, converged and cached) → :mod:`.compare` (relative RMSE, FLIP,
region errors) → :mod:`.still` (one still: all of them in order).
"""

from .camera import Camera
from .compare import compare, region_errors, rel_rmse
from .lights import DirectionalLight, EnvironmentLight, Light, PointLight, SpotLight, parse_light
from .object import boundary_eta, object_of_model, volume_of_dataset
from .picture import VertexPicture, coverage, render_vertex_radiance
from .reference import converged_reference, render_reference
from .tonemap import save_images, tonemap

__all__ = [
    "Camera",
    "VertexPicture",
    "compare",
    "coverage",
    "converged_reference",
    "region_errors",
    "rel_rmse",
    "render_reference",
    "render_vertex_radiance",
    "save_images",
    "tonemap",
    "boundary_eta",
    "object_of_model",
    "volume_of_dataset",
    "Light",
    "DirectionalLight",
    "EnvironmentLight",
    "SpotLight",
    "PointLight",
    "parse_light",
]
