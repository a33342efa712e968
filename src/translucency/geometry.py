r"""Geometry shared by the stages: sample grids and windows, tangent frames, vertex areas, incident points.

* planar samples: the pixel grid :class:`SampleGrid` covering all windows (α's
  support) and the per-pixel distance r, angle θ and grid pixel of each window
  (:func:`window_geometry`), used by the fitter and the evaluation;
* meshes: orthonormal tangent frames around normals (:func:`tangent_frames`),
  the area :math:`A_v` each vertex stands for (:func:`vertex_areas`) and the
  farthest-point choice of incident vertices (:func:`farthest_points`), used by
  acquisition, fitting and rendering; an object's bounds and centre (:func:`object_bounds`), which
  ``translucency info`` prints so that a user can place lights and cameras.

Units: mm, mm², radians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import TranslucencyError


# -- planar samples -------------------------------------------------------------------------
@dataclass
class SampleGrid:
    """The pixel grid covering all windows: α's support.

    Pixel ``[row, col]`` is centred at ``origin + pitch * (col + 1/2, row + 1/2)``.

    Examples
    --------
    >>> corners = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 0.5]])   # three 5 × 5 windows of 0.25 mm pixels
    >>> g = SampleGrid.covering(corners, 0.25, (5, 5))
    >>> g.shape   # (rows, cols): 0.5 mm = 2 pixels more in y, 1 mm = 4 more in x
    (7, 9)
    >>> g.offsets(corners).tolist()   # each window's first pixel (row, col)
    [[0, 0], [0, 4], [2, 0]]
    """

    origin: np.ndarray  # (2,) mm
    pitch: float
    shape: tuple[int, int]

    @classmethod
    def covering(cls, window_origin: np.ndarray, pitch: float, window: tuple[int, int]) -> SampleGrid:
        lo = window_origin.min(axis=0)
        span = np.round((window_origin.max(axis=0) - lo) / pitch).astype(int)
        return cls(lo.astype(np.float64), float(pitch), (int(span[1]) + window[0], int(span[0]) + window[1]))

    def offsets(self, window_origin: np.ndarray) -> np.ndarray:
        """(k, 2) integer (row, col) of each window's first pixel on this grid."""
        o = np.round((window_origin - self.origin) / self.pitch).astype(np.int64)
        return o[:, ::-1]


@dataclass
class WindowGeometry:
    """Per-pixel geometry of a chunk of k windows of H × W pixels (J = H·W).

    Examples
    --------
    >>> g = WindowGeometry(r=np.zeros((1, 4)), theta=np.zeros((1, 4)), pixel=np.arange(8).reshape(2, 4))
    >>> g.r.shape, g.pixel.shape   # k = 2 windows alike: one row of r and θ, a row of pixels each
    ((1, 4), (2, 4))
    """

    r: np.ndarray  # (k or 1, J) mm
    theta: np.ndarray  # (k or 1, J) rad
    pixel: np.ndarray  # (k, J) flat index on the sample grid


def window_geometry(
    x_i: np.ndarray, window_origin: np.ndarray, grid: SampleGrid, window: tuple[int, int]
) -> WindowGeometry:
    """Distances, angles and sample-grid pixels of every window pixel.

    When every window lies alike around its point (offsets x_i − origin equal
    to 10⁻⁵ pixel: points snapped to pixel centres), r and θ are one row (1, J).

    Examples
    --------
    >>> corners = np.array([[0.0, 0.0], [1.0, 0.0]])
    >>> grid = SampleGrid.covering(corners, 0.25, (5, 5))
    >>> x_i = corners + 0.625   # each point at its window's central pixel centre
    >>> g = window_geometry(x_i, corners, grid, (5, 5))
    >>> g.r.shape, g.pixel.shape   # the windows lie alike: r and θ are one row
    ((1, 25), (2, 25))
    >>> float(g.r[0, 12]), g.pixel[:, 12].tolist()   # the central pixel: r = 0, at columns 2 and 6 of row 2
    (0.0, [20, 24])
    """
    h, w = window
    col, row = np.meshgrid(np.arange(w), np.arange(h))
    col, row = col.ravel(), row.ravel()
    rel = window_origin - x_i
    if len(rel) > 1 and np.ptp(rel, axis=0).max() <= grid.pitch * 1e-5:
        rel = rel[:1]
    dx = rel[:, :1] + grid.pitch * (col + 0.5)
    dy = rel[:, 1:] + grid.pitch * (row + 0.5)
    off = grid.offsets(window_origin)
    pixel = (off[:, :1] + row) * grid.shape[1] + (off[:, 1:] + col)
    return WindowGeometry(np.hypot(dx, dy), np.arctan2(dy, dx), pixel)


# -- meshes ---------------------------------------------------------------------------------
def tangent_frames(normals: np.ndarray) -> np.ndarray:
    """Orthonormal frames (t, b, n) as rows, shape (N, 3, 3), around unit normals (N, 3).

    Examples
    --------
    >>> f = tangent_frames(np.array([[0.0, 0.0, 2.0], [1.0, 1.0, 0.0]]))   # normals need not be unit
    >>> f[:, 2].round(4).tolist()   # the last row: the unit normal
    [[0.0, 0.0, 1.0], [0.7071, 0.7071, 0.0]]
    >>> bool(np.allclose(f @ f.transpose(0, 2, 1), np.eye(3)))   # orthonormal
    True
    """
    n = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    helper = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t = np.cross(helper, n)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    return np.stack([t, np.cross(n, t), n], axis=1)


def farthest_points(vertices: np.ndarray, k: int, start: int = 0) -> np.ndarray:
    """Indices of k vertices spread over the surface by farthest-point sampling (Euclidean).

    Examples
    --------
    >>> v = np.array([[0.0, 0, 0], [1, 0, 0], [10, 0, 0], [5, 0, 0]])
    >>> farthest_points(v, 3).tolist()
    [0, 2, 3]
    """
    k = int(k)
    if not 1 <= k <= len(vertices):
        raise TranslucencyError(f"points: need 1 to {len(vertices)} incident points, got {k}")
    chosen = [int(start)]
    d = np.linalg.norm(vertices - vertices[start], axis=1)
    for _ in range(k - 1):
        nxt = int(np.argmax(d))
        chosen.append(nxt)
        d = np.minimum(d, np.linalg.norm(vertices - vertices[nxt], axis=1))
    return np.array(chosen)


def vertex_areas(mesh) -> np.ndarray:
    """A third of the area of the triangles around each vertex, mm².

    ``mesh``: anything with ``vertices``, ``faces`` and ``area_faces`` (a :class:`trimesh.Trimesh`).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> square = SimpleNamespace(vertices=np.zeros((4, 3)), faces=np.array([[0, 1, 2], [0, 2, 3]]),
    ...                          area_faces=np.array([0.5, 0.5]))   # a unit square in two triangles
    >>> a = vertex_areas(square)
    >>> a.round(4).tolist(), round(float(a.sum()), 6)   # the shared corners 0 and 2 stand for twice the area
    ([0.3333, 0.1667, 0.3333, 0.1667], 1.0)
    """

    return np.bincount(mesh.faces.ravel(), np.repeat(mesh.area_faces / 3.0, 3), minlength=len(mesh.vertices))


def object_bounds(vertices) -> dict:
    """The axis-aligned bounds ``[[x, y, z]min, [x, y, z]max]`` of an object's vertices (V, 3) and their
    centre, mm, as plain lists (JSON-ready).

    Examples
    --------
    >>> object_bounds([[0, 0, 0], [2, 4, 6]])
    {'bounds_mm': [[0.0, 0.0, 0.0], [2.0, 4.0, 6.0]], 'centre_mm': [1.0, 2.0, 3.0]}
    """
    v = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    lo, hi = v.min(axis=0), v.max(axis=0)
    return {"bounds_mm": [lo.tolist(), hi.tolist()], "centre_mm": ((lo + hi) / 2).tolist()}


def same_triangles(a, b) -> bool:
    """Whether two (F, 3) face arrays hold the same oriented triangles in any order and from any corner
    (a model file keeps its mesh compressed, its triangles in the codec's order: ``io/mesh_codec.py``).

    Examples
    --------
    >>> same_triangles([[0, 1, 2], [2, 1, 3]], [[1, 3, 2], [2, 0, 1]])
    True
    >>> same_triangles([[0, 1, 2]], [[0, 2, 1]])  # the other orientation
    False
    """
    a, b = np.asarray(a, np.int64), np.asarray(b, np.int64)
    if a.shape != b.shape:
        return False

    def canonical(f):
        turn = np.argmin(f, axis=1)  # each triangle rotated to start at its smallest index
        f = f[np.arange(len(f))[:, None], (turn[:, None] + np.arange(3)) % 3]
        return f[np.lexsort(f.T[::-1])]

    return bool(np.array_equal(canonical(a), canonical(b)))
