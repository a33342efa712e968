r"""Pictures of an object: ours (per-vertex radiance drawn by Mitsuba) and the path-traced reference.

* **ours**: the mesh carries the radiance per vertex (:mod:`.transport`) as an
  attribute; Mitsuba draws it as an area emitter with a ``mesh_attribute``
  radiance (linearly interpolated over each triangle) through the camera —
  so the picture costs one rasterising pass, not a light-transport simulation.
  A dielectric object (η ≠ 1) also gets its smooth surface reflection: a
  ``plastic`` BSDF with no diffuse part is Fresnel reflection off a smooth
  dielectric, and an environment light is in the scene (seen behind the object
  and in its reflection).
* **reference**: the same object, volume, light and camera rendered by Mitsuba's
  ``volpath`` (heterogeneous medium over the bounding box, one grey channel at
  a time as in :mod:`translucency.validate.volpath`), behind a ``null``
  boundary (index-matched) or a smooth ``dielectric`` one.  A dielectric object
  can only be path-traced under an environment light: point, spot and
  directional lights reach its inside through a delta refraction, a path
  ``volpath`` cannot sample.
* **comparison**: relative RMSE over the pixels the object covers, and FLIP
  (NVIDIA's perceptual difference, PyPI ``flip-evaluator``) on tone-mapped images.

Units: radiance in W/(mm² sr) for the lights' W/sr (point) or W/mm² (directional).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import flip_evaluator
import matplotlib.image as mpimg
import numpy as np

from .._validate import TranslucencyError
from ..io.atomic import atomic_path
from ..mitsuba import load_with_mesh, mitsuba, slab_medium_dict
from .lights import EnvironmentLight


@dataclass(frozen=True)
class Camera:
    """A perspective camera (mm, degrees); ``looking_at`` frames an object."""

    origin: tuple
    target: tuple
    up: tuple = (0.0, 0.0, 1.0)
    fov: float = 35.0
    width: int = 320
    height: int = 240

    @classmethod
    def looking_at(cls, mesh, direction=(1.0, -1.6, 0.7), width: int = 320, height: int = 240) -> Camera:
        centre = mesh.bounds.mean(axis=0)
        d = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
        dist = 1.9 * float(np.linalg.norm(mesh.extents))
        return cls(tuple(centre + dist * d), tuple(centre), (0.0, 0.0, 1.0), 35.0, width, height)

    def sensor_dict(self, spp: int) -> dict:
        mi = mitsuba()
        return {
            "type": "perspective",
            "fov": self.fov,
            "to_world": mi.ScalarTransform4f().look_at(
                origin=list(self.origin), target=list(self.target), up=list(self.up)
            ),
            "film": {
                "type": "hdrfilm",
                "width": self.width,
                "height": self.height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": "independent", "sample_count": int(spp)},
        }


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
        An :class:`EnvironmentLight` is drawn behind the object and reflected
        (the reflection of a point, spot or directional light in a smooth
        surface covers no area and is not drawn).

    Examples
    --------
    >>> import trimesh
    >>> ball = trimesh.creation.icosphere(1, radius=5.0)
    >>> pic = VertexPicture(ball, Camera.looking_at(ball, width=8, height=6), spp=1)
    >>> pic.draw(np.ones((len(ball.vertices), 3))).shape
    (6, 8, 3)
    """

    def __init__(self, mesh, camera: Camera, *, spp: int = 4, eta: float = 1.0, light=None):
        mi = mitsuba()
        bsdf = (
            {"type": "diffuse", "reflectance": 0.0}
            if eta == 1.0
            else {"type": "plastic", "diffuse_reflectance": 0.0, "int_ior": float(eta), "ext_ior": 1.0}
        )
        self.n_vertices = len(mesh.vertices)
        scene = {
            "type": "scene",
            "integrator": {"type": "direct"},
            "object": {
                "bsdf": bsdf,
                "emitter": {"type": "area", "radiance": {"type": "mesh_attribute", "name": "vertex_color"}},
            },
            "camera": camera.sensor_dict(spp),
        }
        if isinstance(light, EnvironmentLight):
            scene["sky"] = light.emitter_dict()
        self.scene = load_with_mesh(mesh, scene, colour=np.zeros((self.n_vertices, 3)))
        self.params = mi.traverse(self.scene)

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
    """
    return VertexPicture(mesh, camera, spp=spp, eta=eta, light=light).draw(L)


def coverage(mesh, camera: Camera) -> np.ndarray:
    """(H, W) bool: pixels whose centre ray hits the object."""
    ones = np.ones((len(mesh.vertices), 3))
    cov = render_vertex_radiance(mesh, ones, camera, spp=1)[..., 0] > 0.5
    if not cov.any():
        raise TranslucencyError("camera: sees nothing of the object; move it or point it at the object")
    return cov


def render_reference(
    mesh, volume, light, camera: Camera, *, spp: int = 256, seed: int = 0, eta: float = 1.0
) -> tuple[np.ndarray, float]:
    """The same object path-traced by Mitsuba's ``volpath``; returns (image (H, W, 3), seconds).

    The seconds are the path tracing alone (three grey renders; building the scenes is not counted).

    ``eta`` ≠ 1: a smooth dielectric boundary (environment lights only, see the module docstring).
    """
    mi = mitsuba()
    if eta != 1.0 and not isinstance(light, EnvironmentLight):
        raise TranslucencyError(
            "reference: volpath cannot light a dielectric object with a point, spot or "
            "directional light (a delta refraction); use an env light or an index-matched "
            "data set"
        )
    boundary = (
        {"type": "null"} if eta == 1.0 else {"type": "dielectric", "int_ior": float(eta), "ext_ior": 1.0}
    )
    lo, hi = mesh.bounds
    if not hasattr(light, "emitter_dict"):
        raise TranslucencyError(f"light: no reference for {light!r}")
    emitter = light.emitter_dict()
    seconds = 0.0
    channels = []
    for ch in range(3):
        scene = load_with_mesh(
            mesh,
            {
                "type": "scene",
                "integrator": {"type": "volpath", "max_depth": -1, "rr_depth": 100_000},
                "object": {"bsdf": boundary, "interior": slab_medium_dict(volume, ch, (lo[0], lo[1], hi[2]))},
                "light": emitter,
                "camera": camera.sensor_dict(spp),
            },
        )
        t = time.perf_counter()
        channels.append(np.asarray(mi.render(scene, seed=3 * seed + ch), dtype=np.float64)[..., ch])
        seconds += time.perf_counter() - t
    return np.stack(channels, axis=2), seconds


def tonemap(img: np.ndarray, exposure: float) -> np.ndarray:
    """Linear RGB × exposure → sRGB in [0, 1] (clipped)."""
    x = np.clip(img * exposure, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def rel_rmse(image: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> float:
    """‖image − reference‖ / ‖reference‖ over the pixels of ``mask`` (NaN where there are none)."""
    ref2 = float(np.mean(reference[mask] ** 2)) if mask.any() else 0.0
    return float(np.sqrt(np.mean((image[mask] - reference[mask]) ** 2) / ref2)) if ref2 > 0 else float("nan")


def compare(reference: np.ndarray, ours: np.ndarray, mask: np.ndarray) -> dict:
    """Relative RMSE over the object's pixels and mean FLIP of the tone-mapped pair."""
    exposure = 0.8 / max(float(np.quantile(reference[mask], 0.99)), 1e-30)
    ref_ldr, our_ldr = tonemap(reference, exposure), tonemap(ours, exposure)
    flip_map, mean_flip, _ = flip_evaluator.evaluate(
        ref_ldr.astype(np.float32), our_ldr.astype(np.float32), "LDR"
    )
    fm = np.asarray(flip_map, dtype=np.float64)
    fm = fm[..., 0] if fm.ndim == 3 else fm  # the per-pixel error (a grey image)
    return {
        "rel_rmse": rel_rmse(ours, reference, mask),
        "flip_mean_object": float(fm[mask].mean()),
        "flip_mean_image": float(mean_flip),
        "exposure": exposure,
        "flip_map": fm,
    }


def save_images(img: np.ndarray, stem: Path, exposure: float) -> tuple[Path, Path]:
    """``stem.exr`` (linear HDR, via Mitsuba's Bitmap/OpenEXR) and ``stem.png`` (tone-mapped), atomically."""
    mi = mitsuba()
    stem = Path(stem)
    exr, png = stem.with_suffix(".exr"), stem.with_suffix(".png")
    with atomic_path(exr) as tmp:
        mi.Bitmap(img.astype(np.float32)).write(str(tmp))
    with atomic_path(png) as tmp:
        mpimg.imsave(tmp, tonemap(img, exposure))
    return exr, png
