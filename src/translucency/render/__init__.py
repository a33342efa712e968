"""Rendering fitted objects, one stage walked down once.

:mod:`.object` (mesh, volume and boundary of a model) → :mod:`.lights` → :mod:`.transport`
(irradiance per vertex, the sparse transport and its far field :mod:`._far_field`, :func:`default_radius`)
→ :mod:`.camera` → :mod:`.picture` (our picture from the radiance per vertex) → :mod:`.tonemap` (sRGB,
the files) → :mod:`.reference` (the ``volpath`` reference, converged and cached) → :mod:`.compare`
(relative RMSE, FLIP, region errors) → :mod:`.figure` (Figure 2: all of them in order).
"""

from .camera import Camera
from .compare import compare, region_errors, rel_rmse
from .lights import DirectionalLight, EnvironmentLight, PointLight, SpotLight, parse_light
from .object import boundary_eta, object_of_model, volume_of_dataset
from .picture import VertexPicture, coverage, render_vertex_radiance
from .reference import converged_reference, render_reference
from .tonemap import save_images, tonemap
from .transport import (
    MAX_PAIRS,
    default_radius,
    relight_object,
    relight_vertices,
    transport_matrices,
    vertex_irradiance,
)

__all__ = [
    "Camera",
    "VertexPicture",
    "compare",
    "coverage",
    "converged_reference",
    "default_radius",
    "MAX_PAIRS",
    "region_errors",
    "rel_rmse",
    "render_reference",
    "render_vertex_radiance",
    "save_images",
    "tonemap",
    "boundary_eta",
    "object_of_model",
    "volume_of_dataset",
    "DirectionalLight",
    "EnvironmentLight",
    "SpotLight",
    "PointLight",
    "parse_light",
    "relight_object",
    "relight_vertices",
    "transport_matrices",
    "vertex_irradiance",
]
