"""Rendering fitted objects: irradiance per vertex, sparse transport, Mitsuba pictures, the volpath reference."""

from .image import Camera, VertexPicture, compare, render_reference, render_vertex_radiance, save_images
from .transport import (DirectionalLight, EnvironmentLight, PointLight, SpotLight, parse_light, relight_vertices,
                        transport_matrices, vertex_irradiance)

__all__ = ["Camera", "VertexPicture", "compare", "render_reference", "render_vertex_radiance", "save_images", "DirectionalLight",
           "EnvironmentLight", "SpotLight", "PointLight", "parse_light", "relight_vertices", "transport_matrices", "vertex_irradiance"]
