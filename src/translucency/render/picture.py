r"""Our picture of an object: the radiance per vertex (:mod:`.transport`) drawn by Mitsuba, and its files.

The mesh carries the radiance per vertex as an attribute; Mitsuba draws it as an area emitter with a
``mesh_attribute`` radiance (linearly interpolated over each triangle) through the camera — so the
picture costs one rasterising pass, not a light-transport simulation.  A dielectric object (η ≠ 1)
also gets its smooth surface reflection: a ``plastic`` BSDF with no diffuse part is Fresnel reflection
off a smooth dielectric, and an environment light is in the scene (seen behind the object and in its
reflection).

Units: radiance in W/(mm² sr) for the lights' W/sr (point) or W/mm² (directional).
"""

from __future__ import annotations

import numpy as np

from .._validate import TranslucencyError
from ..mitsuba import mitsuba, pinhole_sensor_dict, vertex_radiance_scene
from .camera import Camera


class VertexPicture:
    """A picture of the mesh through the camera, prepared once; :meth:`draw` paints radiance per vertex.

    The Mitsuba scene (mesh, BSDF, emitters, camera) is built once; a new
    radiance only replaces the mesh's ``vertex_color`` attribute — as the
    transport is prepared once and a light costs one sparse product.

    Parameters
    ----------
    mesh : trimesh.Trimesh
    camera : Camera
    spp : int
        Samples per pixel (anti-aliasing; the picture has no noise otherwise).
    eta : float
        ≠ 1: the surface also reflects (smooth dielectric, Fresnel).
    light : optional
        A light that is not a delta light (:attr:`~.lights.Light.delta`: an environment) is drawn
        behind the object and reflected (the reflection of a point, spot or directional light in a
        smooth surface covers no area and is not drawn).

    Examples
    --------
    >>> import trimesh
    >>> ball = trimesh.creation.icosphere(1, radius=5.0)
    >>> pic = VertexPicture(ball, Camera.looking_at(ball, width=8, height=6), spp=1)
    >>> pic.draw(np.ones((len(ball.vertices), 3))).shape
    (6, 8, 3)
    """

    def __init__(self, mesh, camera: Camera, *, spp: int = 4, eta: float = 1.0, light=None):
        self.n_vertices = len(mesh.vertices)
        environment = None if light is None or light.delta else light.emitter_dict()
        self.scene = vertex_radiance_scene(
            mesh, pinhole_sensor_dict(camera, spp), eta=eta, environment=environment
        )
        self.params = mitsuba().traverse(self.scene)

    def draw(self, L: np.ndarray, seed: int = 0) -> np.ndarray:
        """(H, W, 3) picture of radiance L (V, 3) per vertex."""
        mi = mitsuba()
        L = np.asarray(L, dtype=np.float32)
        if L.shape != (self.n_vertices, 3):
            raise TranslucencyError(
                f"radiance: expected ({self.n_vertices}, 3) values per vertex, got {L.shape}"
            )
        self.params["object.vertex_color"] = mi.Float(np.maximum(L, 0.0).ravel())
        self.params.update()
        return np.asarray(mi.render(self.scene, seed=seed), dtype=np.float64)


def render_vertex_radiance(
    mesh, L: np.ndarray, camera: Camera, *, spp: int = 4, eta: float = 1.0, light=None
) -> np.ndarray:
    """Draw the mesh with radiance L (V, 3) per vertex through the camera; returns (H, W, 3).

    One-off :class:`VertexPicture` (see there for ``eta`` and ``light``).

    Examples
    --------
    >>> import trimesh
    >>> ball = trimesh.creation.icosphere(2, radius=5.0)
    >>> camera = Camera.looking_at(ball, width=8, height=6)
    >>> L = np.tile([0.1, 0.2, 0.3], (len(ball.vertices), 1))  # W/(mm² sr), the same at every vertex
    >>> picture = render_vertex_radiance(ball, L, camera, spp=1)
    >>> picture.shape  # (height, width, RGB)
    (6, 8, 3)
    >>> picture[3, 4].round(6), picture[0, 0]  # the radiance itself, unshaded; nothing behind the object
    (array([0.1, 0.2, 0.3]), array([0., 0., 0.]))
    """
    return VertexPicture(mesh, camera, spp=spp, eta=eta, light=light).draw(L)


def coverage(mesh, camera: Camera) -> np.ndarray:
    """(H, W) bool: pixels whose centre ray hits the object.

    Examples
    --------
    >>> import trimesh
    >>> box = trimesh.creation.box(extents=(10.0, 10.0, 10.0))  # its top face at z = 5 mm
    >>> fov = 2 * np.degrees(np.arctan(10.0 / 95.0))  # 20 mm across at the top face, 95 mm below
    >>> above = Camera((0.0, 0.0, 100.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), fov, width=8, height=8)
    >>> coverage(box, above).astype(int)  # the 10 mm face: the middle 4 × 4 pixels
    array([[0, 0, 0, 0, 0, 0, 0, 0],
           [0, 0, 0, 0, 0, 0, 0, 0],
           [0, 0, 1, 1, 1, 1, 0, 0],
           [0, 0, 1, 1, 1, 1, 0, 0],
           [0, 0, 1, 1, 1, 1, 0, 0],
           [0, 0, 1, 1, 1, 1, 0, 0],
           [0, 0, 0, 0, 0, 0, 0, 0],
           [0, 0, 0, 0, 0, 0, 0, 0]])
    >>> away = Camera((0.0, 0.0, 100.0), (0.0, 0.0, 200.0), (0.0, 1.0, 0.0), width=8, height=8)
    >>> coverage(box, away)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: camera: sees nothing of the object; move it or point it ...
    """
    ones = np.ones((len(mesh.vertices), 3))
    cov = render_vertex_radiance(mesh, ones, camera, spp=1)[..., 0] > 0.5
    if not cov.any():
        raise TranslucencyError("camera: sees nothing of the object; move it or point it at the object")
    return cov
