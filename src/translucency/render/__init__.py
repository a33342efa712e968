"""Rendering fitted objects, one stage walked down once.

:mod:`.object` (mesh, volume and boundary of a model) → :mod:`.lights` (one protocol, :class:`Light`) →
:mod:`.irradiance` (per vertex, with shadows) → :mod:`.parameters` (per vertex, blended from the fit) →
:mod:`.transport` (the sparse near matrices and the far field :mod:`._far_field`, :func:`default_radius`) →
:mod:`.relight` (radiance per vertex) → :mod:`.camera` → :mod:`.picture` (our picture from the radiance per
vertex) → :mod:`.tonemap` (sRGB, the files) → :mod:`.reference` (the ``volpath`` reference, converged and
cached) → :mod:`.compare` (relative RMSE, FLIP, region errors) → :mod:`.figure` (Figure 2: all of them in
order).
"""

from .camera import Camera
from .compare import compare, region_errors, rel_rmse
from .irradiance import vertex_irradiance
from .lights import DirectionalLight, EnvironmentLight, Light, PointLight, SpotLight, parse_light
from .object import boundary_eta, object_of_model, volume_of_dataset
from .picture import VertexPicture, coverage, render_vertex_radiance
from .reference import converged_reference, render_reference
from .relight import relight_object, relight_vertices
from .tonemap import save_images, tonemap
from .transport import MAX_PAIRS, default_radius, transport_matrices

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
    "Light",
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
