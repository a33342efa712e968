"""How our picture compares with the reference: relative RMSE, FLIP, and the errors by region.

* :func:`rel_rmse`: relative RMSE over the pixels the object covers;
* :func:`compare`: that, and FLIP (NVIDIA's perceptual difference, PyPI ``flip-evaluator``: the ``flip``
  extra; without it the relative RMSE alone, :data:`FLIP_SKIPPED` says so) on the tone-mapped pair;
* :func:`region_errors`: the relative RMSE in the regions where a local model is expected to err
  (thin and thick parts, the shadow edge, the unlit side, the silhouette).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_erosion

from .._extras import optional, skipped
from ..mitsuba import rays
from .camera import Camera
from .picture import VertexPicture
from .tonemap import auto_exposure, tonemap

#: the information line of a comparison without the flip extra
FLIP_SKIPPED = skipped("flip", "FLIP beside the relative RMSE")


def rel_rmse(image: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> float:
    """‖image − reference‖ / ‖reference‖ over the pixels of ``mask`` (NaN where there are none).

    Examples
    --------
    >>> reference = np.array([[1.0, 2.0], [3.0, 4.0]])
    >>> mask = np.array([[True, True], [True, False]])
    >>> rel_rmse(reference, reference, mask)
    0.0
    >>> round(rel_rmse(1.1 * reference, reference, mask), 6)  # 10 % too bright everywhere
    0.1
    >>> ours = reference.copy()
    >>> ours[1, 1] = 99.0  # outside the mask: not counted
    >>> rel_rmse(ours, reference, mask)
    0.0
    >>> rel_rmse(reference, reference, np.zeros((2, 2), bool))  # no pixels
    nan
    """
    ref2 = float(np.mean(reference[mask] ** 2)) if mask.any() else 0.0
    return float(np.sqrt(np.mean((image[mask] - reference[mask]) ** 2) / ref2)) if ref2 > 0 else float("nan")


def compare(reference: np.ndarray, ours: np.ndarray, mask: np.ndarray) -> dict:
    """Relative RMSE over the object's pixels and mean FLIP of the tone-mapped pair.

    Without the ``flip`` extra the FLIP entries (``flip_mean_object``, ``flip_mean_image``) are left out
    and ``flip_map`` is None (:data:`FLIP_SKIPPED`; :func:`flip_available`).

    Examples
    --------
    >>> reference = np.full((8, 8, 3), 0.2)
    >>> mask = np.zeros((8, 8), bool)
    >>> mask[2:6, 2:6] = True
    >>> same = compare(reference, reference, mask)
    >>> same["rel_rmse"], same["flip_mean_image"], same["exposure"]  # exposure: AUTO_KEY 0.8 / 0.2
    (0.0, 0.0, 4.0)
    >>> off = compare(reference, 1.5 * reference, mask)
    >>> round(off["rel_rmse"], 6), off["flip_mean_image"] > 0, off["flip_map"].shape
    (0.5, True, (8, 8))

    The map is FLIP's error itself: nil where the images agree, and over every pixel its mean is FLIP's
    own mean of the image:

    >>> same["flip_mean_object"]
    0.0
    >>> everywhere = compare(reference, 1.5 * reference, np.ones((8, 8), bool))
    >>> bool(np.isclose(everywhere["flip_mean_object"], everywhere["flip_mean_image"], rtol=1e-6))
    True
    """
    error = rel_rmse(ours, reference, mask)
    exposure = auto_exposure(reference, mask)
    flip_evaluator = optional("flip")
    if flip_evaluator is None:  # the relative RMSE alone
        return {"rel_rmse": error, "exposure": exposure, "flip_map": None}
    ref_ldr, our_ldr = tonemap(reference, exposure), tonemap(ours, exposure)
    # the per-pixel FLIP error itself (applyMagma=False): with flip-evaluator's default the map comes back
    # coloured by magma, whose red channel is no error (0.0015 where the images agree, 0.997 at 0.84)
    flip_map, mean_flip, _ = flip_evaluator.evaluate(
        ref_ldr.astype(np.float32), our_ldr.astype(np.float32), "LDR", applyMagma=False
    )
    fm = np.asarray(flip_map, dtype=np.float64)
    fm = fm[..., 0] if fm.ndim == 3 else fm  # (H, W, 1) → (H, W)
    return {
        "rel_rmse": error,
        "flip_mean_object": float(fm[mask].mean()),
        "flip_mean_image": float(mean_flip),
        "exposure": exposure,
        "flip_map": fm,
    }


def flip_available() -> bool:
    """Whether :func:`compare` measures FLIP (the ``flip`` extra is installed).

    Examples
    --------
    >>> flip_available()   # installed here
    True
    """
    return optional("flip") is not None


def region_errors(
    mesh, scene, camera: Camera, E: np.ndarray, reference: np.ndarray, ours: np.ndarray, mask: np.ndarray
) -> dict:
    """Relative RMSE of ours against the reference in the regions where a local model is expected to err.

    Regions (pixels of the object; vertex properties drawn through the camera):
    ``thin`` (< 10 mm through the object along the normal), ``thick`` (> 25 mm), ``shadow edge``
    (vertices on either side of the lit/unlit boundary, one ring wide), ``unlit`` (no direct light),
    ``silhouette`` (the outermost pixel ring of the object). Returns {region: {rel_rmse, brightness,
    pixels}}.

    Examples
    --------
    >>> import trimesh
    >>> from translucency.mitsuba import mesh_scene
    >>> from translucency.render import DirectionalLight, coverage, render_vertex_radiance
    >>> from translucency.transport import vertex_irradiance
    >>> ball = trimesh.creation.icosphere(2, radius=20.0)  # 40 mm through: thick everywhere, nothing thin
    >>> scene, camera = mesh_scene(ball), Camera.looking_at(ball, direction=(1, 0, 0), width=16, height=12)
    >>> E = vertex_irradiance(ball, scene, DirectionalLight((0.0, 0.0, -1.0)))  # lit from above
    >>> reference = render_vertex_radiance(ball, np.repeat(E[:, None], 3, axis=1) + 0.1, camera, spp=1)
    >>> mask = coverage(ball, camera)
    >>> errors = region_errors(ball, scene, camera, E, reference, 1.1 * reference, mask)  # 10 % too bright
    >>> {name: round(e["rel_rmse"], 6) for name, e in errors.items()}
    {'all': 0.1, 'thin': nan, 'thick': 0.1, 'shadow edge': 0.1, 'unlit': 0.1, 'silhouette': 0.1}
    >>> round(errors["unlit"]["brightness"], 6), errors["all"]["pixels"] == int(mask.sum())
    (1.1, True)
    """
    E = np.asarray(E, dtype=np.float64)
    lit = (E.sum(axis=1) if E.ndim == 2 else E) > 0
    edges = np.asarray(mesh.edges_unique)
    flip = lit[edges[:, 0]] != lit[edges[:, 1]]
    edge_v = np.zeros(len(lit), dtype=bool)
    edge_v[edges[flip].ravel()] = True
    ring = edge_v.copy()  # one ring more
    ring[edges[edge_v[edges[:, 0]] | edge_v[edges[:, 1]]].ravel()] = True
    thick = vertex_thickness(mesh, scene)
    flags = np.stack([thick < 10.0, thick > 25.0, ring], axis=1).astype(np.float64)
    picture = VertexPicture(mesh, camera, spp=1)
    drawn = picture.draw(flags) > 0.5
    unlit = picture.draw(np.repeat((~lit)[:, None], 3, axis=1).astype(np.float64))[..., 0] > 0.5
    regions = {
        "all": mask,
        "thin": drawn[..., 0] & mask,
        "thick": drawn[..., 1] & mask,
        "shadow edge": drawn[..., 2] & mask,
        "unlit": unlit & mask,
        "silhouette": mask & ~binary_erosion(mask),
    }
    return {
        name: {
            "rel_rmse": rel_rmse(ours, reference, sel),
            # the sign of the error: mean of ours over the reference's in the region (nan where empty)
            "brightness": float(ours[sel].mean() / reference[sel].mean()) if sel.any() else float("nan"),
            # the hue: each channel's share of the light in the region, ours over the reference's (R, G, B;
            # 1 is right)
            "colour": _ratio(channel_shares(ours, sel), channel_shares(reference, sel)).tolist(),
            "pixels": int(sel.sum()),
        }
        for name, sel in regions.items()
    }


def _ratio(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a / b, nan where b is 0 or not a number."""
    ok = np.isfinite(b) & (b > 0)
    return np.divide(a, b, out=np.full(np.shape(a), np.nan), where=ok)


def channel_shares(image: np.ndarray, sel: np.ndarray) -> np.ndarray:
    """Each channel's share of the light over the pixels ``sel``: Σ I_c / Σ_c' Σ I_c', (3,) (nan where
    none is lit).

    Examples
    --------
    >>> image = np.ones((2, 2, 3)) * [0.5, 0.3, 0.2]
    >>> channel_shares(image, np.ones((2, 2), bool)).round(3).tolist()
    [0.5, 0.3, 0.2]
    """
    sums = np.asarray(image, dtype=np.float64)[sel].sum(axis=0)
    total = sums.sum()
    return sums / total if total > 0 else np.full(3, np.nan)


def vertex_thickness(mesh, scene) -> np.ndarray:
    """Distance (mm) from each vertex straight inwards (along −n) to the other side of the object."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    si = scene.ray_intersect(rays(v - n * 1e-4 * float(np.max(mesh.extents)), -n))
    return np.where(np.asarray(si.is_valid()), np.asarray(si.t, dtype=np.float64), np.inf)
