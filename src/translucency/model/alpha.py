r"""The modulation texture :math:`\alpha(\vec x_o)` of eq. (1).

:math:`\alpha` is a dimensionless, non-negative scale on the light leaving at
:math:`\vec x_o`; it models volumetric structure close to the outgoing point
that the per-:math:`\vec x_i` fall-off cannot.  Two carriers:

* :class:`PlanarAlpha` — an image over a planar sample: pixel ``[row, col]``
  is centred at ``origin + pitch * (col + 1/2, row + 1/2)`` mm (x along
  columns, y along rows), looked up by nearest pixel and clamped at the edge;
* :class:`VertexAlpha` — one value per mesh vertex, looked up by nearest
  vertex (renderers that already know the vertex pass the value directly).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError, as_float_array, check_nonnegative, check_positive


@dataclass(frozen=True, eq=False)
class PlanarAlpha:
    """Modulation texture on a pixel grid over a planar sample.

    Parameters
    ----------
    values : array_like, shape (H, W)
        :math:`\\alpha` per pixel, >= 0, dimensionless.
    origin : array_like, shape (2,)
        Position (x, y) in mm of the grid's corner (outer edge of pixel [0, 0]).
    pitch : float
        Pixel size in mm.

    Examples
    --------
    >>> import numpy as np
    >>> from translucency.model import PlanarAlpha
    >>> a = PlanarAlpha.uniform((4, 4), origin=(0.0, 0.0), pitch=0.5)
    >>> a.at(np.array([[0.1, 1.9]]))
    array([1.])
    """

    values: np.ndarray
    origin: np.ndarray
    pitch: float

    def __post_init__(self):
        values = as_float_array("alpha", self.values, ndim=2)
        check_nonnegative("alpha", values)
        if values.size == 0:
            raise TranslucencyError("alpha: empty texture")
        origin = as_float_array("alpha origin", self.origin, shape=(2,))
        pitch = float(as_float_array("alpha pitch", self.pitch, ndim=0))
        check_positive("alpha pitch", np.asarray(pitch))
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "origin", origin)
        object.__setattr__(self, "pitch", pitch)

    @classmethod
    def uniform(cls, shape, origin=(0.0, 0.0), pitch=1.0) -> PlanarAlpha:
        """A texture of ones: no modulation."""
        return cls(np.ones(shape), np.asarray(origin, dtype=float), pitch)

    @property
    def shape(self) -> tuple[int, int]:
        return self.values.shape

    def pixel_of(self, x_o: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(row, col) of the pixel containing each point, clamped to the grid."""
        x_o = np.asarray(x_o, dtype=np.float64)
        col = np.floor((x_o[..., 0] - self.origin[0]) / self.pitch).astype(np.int64)
        row = np.floor((x_o[..., 1] - self.origin[1]) / self.pitch).astype(np.int64)
        h, w = self.values.shape
        return np.clip(row, 0, h - 1), np.clip(col, 0, w - 1)

    def at(self, x_o: np.ndarray) -> np.ndarray:
        """:math:`\\alpha` at points ``x_o`` of shape (..., 2) in mm."""
        row, col = self.pixel_of(x_o)
        return self.values[row, col]


@dataclass(frozen=True, eq=False)
class VertexAlpha:
    """Modulation texture with one value per mesh vertex.

    Parameters
    ----------
    values : array_like, shape (V,)
        :math:`\\alpha` per vertex, >= 0.
    vertices : array_like, shape (V, 3)
        Vertex positions in mm, used to look up arbitrary points.

    Examples
    --------
    >>> import numpy as np
    >>> from translucency.model import VertexAlpha
    >>> a = VertexAlpha([1.0, 2.0, 3.0], np.eye(3))   # α = 1, 2, 3 at the unit points on x, y, z
    >>> a.at(np.array([[0.9, 0.1, 0.0], [0.0, 0.2, 0.7]]))   # the nearest vertex's value
    array([1., 3.])
    """

    values: np.ndarray
    vertices: np.ndarray

    def __post_init__(self):
        values = as_float_array("alpha", self.values, ndim=1)
        check_nonnegative("alpha", values)
        vertices = as_float_array("alpha vertices", self.vertices, shape=(values.shape[0], 3))
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "_tree", None)

    @classmethod
    def uniform(cls, vertices) -> VertexAlpha:
        """A texture of ones: no modulation."""
        vertices = np.asarray(vertices, dtype=float)
        return cls(np.ones(len(vertices)), vertices)

    @property
    def shape(self) -> tuple[int]:
        return self.values.shape

    def at(self, x_o: np.ndarray) -> np.ndarray:
        """:math:`\\alpha` of the vertex nearest to each point of shape (..., 3)."""
        if self._tree is None:
            from scipy.spatial import cKDTree  # heavy: SciPy loads only where α is looked up on a mesh

            object.__setattr__(self, "_tree", cKDTree(self.vertices))
        x_o = np.asarray(x_o, dtype=np.float64)
        _, idx = self._tree.query(x_o.reshape(-1, 3))
        return self.values[idx].reshape(x_o.shape[:-1])


Modulation = PlanarAlpha | VertexAlpha
