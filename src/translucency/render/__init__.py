"""Rendering fitted objects: lights, irradiance per vertex, sparse transport, Mitsuba pictures, the volpath
reference, Figure 2."""

from .image import Camera, VertexPicture, compare, render_reference, render_vertex_radiance, save_images
from .lights import DirectionalLight, EnvironmentLight, PointLight, SpotLight, parse_light
from .transport import relight_vertices, transport_matrices, vertex_irradiance

__all__ = [
    "Camera",
    "VertexPicture",
    "compare",
    "render_reference",
    "render_vertex_radiance",
    "save_images",
    "DirectionalLight",
    "EnvironmentLight",
    "SpotLight",
    "PointLight",
    "parse_light",
    "relight_vertices",
    "transport_matrices",
    "vertex_irradiance",
]
