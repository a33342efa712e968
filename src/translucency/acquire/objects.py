r"""Procedural translucent objects: the default "alabaster pig" figurine.

The pig is the zero level set of a signed distance function built from
ellipsoids (body, head, snout, ears, legs, tail) joined by a smooth minimum,

.. math:: \operatorname{smin}_k(a, b) = \min(a, b) - \frac{h^2 k}{4},\qquad
          h = \max(k - |a - b|, 0)/k,

so the parts blend into one smooth surface without creases, then polygonised by
marching cubes (scikit-image) on a grid of ``voxel_mm`` and wrapped in a
``trimesh.Trimesh`` in millimetres.  It is generated here — no download — and
is watertight by construction (marching cubes of a bounded field whose box
has a margin of empty space).
"""

from __future__ import annotations

import numpy as np
import trimesh
from skimage.measure import marching_cubes

from .._validate import TranslucencyError

# (centre mm, semi-axes mm) of the parts of a pig ~ 85 mm long, standing on z = 0
_PIG_PARTS = [
    ((0.0, 0.0, 24.0), (30.0, 17.0, 16.0)),  # body
    ((30.0, 0.0, 30.0), (12.0, 11.0, 11.0)),  # head
    ((42.0, 0.0, 27.0), (5.0, 6.0, 5.0)),  # snout
    ((27.0, 7.0, 41.0), (3.0, 5.0, 6.0)),  # ears
    ((27.0, -7.0, 41.0), (3.0, 5.0, 6.0)),
    ((17.0, 9.0, 8.0), (4.5, 4.5, 9.0)),  # legs
    ((17.0, -9.0, 8.0), (4.5, 4.5, 9.0)),
    ((-17.0, 9.0, 8.0), (4.5, 4.5, 9.0)),
    ((-17.0, -9.0, 8.0), (4.5, 4.5, 9.0)),
    ((-31.0, 0.0, 30.0), (4.0, 2.5, 2.5)),  # tail
]


def _ellipsoid_sdf(p: np.ndarray, centre, axes) -> np.ndarray:
    """Approximate signed distance to an ellipsoid (exact on the axes), mm."""
    q = (p - np.asarray(centre)) / np.asarray(axes)
    return (np.linalg.norm(q, axis=-1) - 1.0) * min(axes)


def _smin(a: np.ndarray, b: np.ndarray, k: float) -> np.ndarray:
    """Polynomial smooth minimum of two distance fields (blend width k, mm)."""
    h = np.maximum(k - np.abs(a - b), 0.0) / k
    return np.minimum(a, b) - h * h * k / 4.0


def pig_sdf(p: np.ndarray, blend_mm: float = 5.0) -> np.ndarray:
    """Signed distance (negative inside) of the pig at points ``p`` (..., 3), mm."""
    d = None
    for centre, axes in _PIG_PARTS:
        e = _ellipsoid_sdf(p, centre, axes)
        d = e if d is None else _smin(d, e, blend_mm)
    return d


def make_pig(voxel_mm: float = 0.65):
    """The default object: a smooth, watertight pig figurine in mm (trimesh.Trimesh).

    Parameters
    ----------
    voxel_mm : float
        Marching-cubes grid spacing; 0.65 mm gives about 27 k vertices.

    Examples
    --------
    >>> pig = make_pig(3.0)
    >>> bool(pig.is_watertight), pig.bounds.round(0).tolist()[0][2] >= -1
    (True, True)
    """

    if not (np.isfinite(voxel_mm) and 0.2 <= voxel_mm <= 10.0):
        raise TranslucencyError(f"voxel: the pig's grid spacing must lie in [0.2, 10] mm, got {voxel_mm}")
    lo = np.array([-40.0, -24.0, -4.0])
    hi = np.array([52.0, 24.0, 52.0])
    axes = [np.arange(lo[k], hi[k] + voxel_mm, voxel_mm) for k in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    field = pig_sdf(grid)
    verts, faces, _, _ = marching_cubes(field, level=0.0, spacing=(voxel_mm,) * 3)
    # faces must point outwards (positive volume)
    mesh = trimesh.Trimesh(verts + lo, faces, process=True)
    # marching cubes emits a few zero-area triangles where the surface grazes a grid node
    mesh.update_faces(mesh.nondegenerate_faces())
    mesh.remove_unreferenced_vertices()
    mesh.merge_vertices()
    if mesh.volume < 0:
        mesh.invert()
    return mesh
