r"""The object a model describes: where its surface ends, seen from each incident point.

Light that enters at :math:`\vec x_i` leaves through the object's own surface;
a profile that places energy beyond the surface's edge describes a larger
object.  Each variant answers one question, the distance (mm) from
:math:`\vec x_i` to the edge along the tangent-plane angle θ
(:meth:`ObjectExtent.distance`):

``Rectangle``     a planar sample's top face :math:`[x_0, x_1] \times [y_0, y_1]`
                  (what its data set's header says the sample is, or α's
                  support: the sample is at least as large as the windows seen);
``Diameter``      an object of a given diameter (a mesh: the diagonal of its
                  bounding box; no two points of it lie farther apart);
``SemiInfinite``  a semi-infinite slab (Jensen's measured materials): no edge.

:func:`extent_from_dict` reads what :meth:`ObjectExtent.as_dict` wrote (the
model file's ``object`` header field).  Units: mm.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from .._validate import TranslucencyError


class ObjectExtent(ABC):
    """Protocol: the edge of the object a model describes, seen from its incident points.

    Examples
    --------
    >>> [isinstance(e, ObjectExtent) for e in (SemiInfinite(), Diameter(10.0), Rectangle((0, 0), (4, 3)))]
    [True, True, True]
    >>> Rectangle((0, 0), (4, 3)).size_mm   # the diameter: the rectangle's diagonal
    5.0
    """

    #: the variant's name in a model file's header
    kind = "abstract"

    @property
    @abstractmethod
    def size_mm(self) -> float:
        """The object's size: its diameter in mm (inf for a semi-infinite slab)."""

    @abstractmethod
    def distance(self, x_i: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """(N, T) distance (mm) from each incident point ``x_i`` (N, D) to the edge along the angles
        ``theta`` (T,) of its tangent plane; inf where there is no edge."""

    @abstractmethod
    def describe(self) -> str:
        """The object in words, for a person ("a 32 x 32 mm sample")."""

    @abstractmethod
    def as_dict(self) -> dict:
        """JSON-friendly record (the model file's ``object`` header field)."""

    @classmethod
    @abstractmethod
    def from_dict(cls, record: dict) -> ObjectExtent:
        """The extent of a record :meth:`as_dict` wrote."""

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.as_dict()}>"


class SemiInfinite(ObjectExtent):
    """A semi-infinite slab: every profile's energy lies on its surface.

    Examples
    --------
    >>> s = SemiInfinite()
    >>> s.size_mm, s.distance(np.zeros((1, 2)), np.array([0.0, 1.0]))   # no edge in any direction
    (inf, array([[inf, inf]]))
    """

    kind = "semi-infinite"

    @property
    def size_mm(self) -> float:
        return math.inf

    def distance(self, x_i, theta):
        return np.full((len(x_i), len(theta)), np.inf)

    def describe(self) -> str:
        return "a semi-infinite slab"

    def as_dict(self) -> dict:
        return {"kind": self.kind}

    @classmethod
    def from_dict(cls, record):
        return cls()


class Diameter(ObjectExtent):
    """An object no two points of which lie farther apart than ``size`` mm (a mesh's bounding-box diagonal):
    energy farther than that from x_i is beyond it in every direction.

    Examples
    --------
    >>> d = Diameter(10.0)
    >>> d.distance(np.zeros((2, 3)), np.array([0.0, np.pi])).tolist()   # the same from every point, every way
    [[10.0, 10.0], [10.0, 10.0]]
    >>> d.describe(), extent_from_dict(d.as_dict()).size_mm
    ('a 10 mm object', 10.0)
    """

    kind = "diameter"

    def __init__(self, size: float):
        size = float(size)
        if not (size > 0 and math.isfinite(size)):
            raise TranslucencyError(f"size: an object's diameter must be > 0 mm and finite, got {size}")
        self.size = size

    @property
    def size_mm(self) -> float:
        return self.size

    def distance(self, x_i, theta):
        return np.full((len(x_i), len(theta)), self.size)

    def describe(self) -> str:
        return f"a {self.size:.3g} mm object"

    def as_dict(self) -> dict:
        return {"kind": self.kind, "size_mm": self.size}

    @classmethod
    def from_dict(cls, record):
        return cls(record.get("size_mm", float("nan")))


class Rectangle(ObjectExtent):
    """A planar sample's top face, the rectangle from corner ``lo`` = (x0, y0) to ``hi`` = (x1, y1) in mm.

    Examples
    --------
    >>> r = Rectangle((0, 0), (32, 16))
    >>> r.distance(np.array([[16.0, 8.0]]), np.array([0.0, np.pi / 2]))   # from the centre along +x, +y
    array([[16.,  8.]])
    >>> r.describe()
    'a 32 x 16 mm sample'
    """

    kind = "rectangle"

    def __init__(self, lo, hi):
        self.lo = np.asarray(lo, dtype=np.float64).reshape(2)
        self.hi = np.asarray(hi, dtype=np.float64).reshape(2)
        if not (np.isfinite(self.lo).all() and np.isfinite(self.hi).all() and (self.hi > self.lo).all()):
            raise TranslucencyError(
                f"extent: a sample's rectangle needs finite corners lo < hi, got {self.lo.tolist()}, "
                f"{self.hi.tolist()}"
            )

    @property
    def size_mm(self) -> float:
        return float(np.hypot(*(self.hi - self.lo)))

    def distance(self, x_i, theta):
        # the ray x_i + t (cos θ, sin θ) leaves the rectangle at the nearer of its x and y walls
        x = np.asarray(x_i, dtype=np.float64)[:, :2]
        cos, sin = np.cos(theta)[None, :], np.sin(theta)[None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            tx = np.where(cos > 0, (self.hi[0] - x[:, :1]) / cos, (self.lo[0] - x[:, :1]) / cos)
            ty = np.where(sin > 0, (self.hi[1] - x[:, 1:]) / sin, (self.lo[1] - x[:, 1:]) / sin)
        tx = np.where(cos == 0, np.inf, tx)
        ty = np.where(sin == 0, np.inf, ty)
        return np.maximum(np.minimum(tx, ty), 0.0)  # a point outside the rectangle: all beyond it

    def describe(self) -> str:
        w, h = self.hi - self.lo
        return f"a {w:.3g} x {h:.3g} mm sample"

    def as_dict(self) -> dict:
        return {"kind": self.kind, "lo": self.lo.tolist(), "hi": self.hi.tolist()}

    @classmethod
    def from_dict(cls, record):
        return cls(record.get("lo", [np.nan] * 2), record.get("hi", [np.nan] * 2))


#: the variants by their header name
EXTENT_KINDS = {cls.kind: cls for cls in (SemiInfinite, Diameter, Rectangle)}


def extent_from_dict(record: dict) -> ObjectExtent:
    """The extent :meth:`ObjectExtent.as_dict` recorded.

    Examples
    --------
    >>> extent_from_dict(Rectangle((0, 0), (32, 32)).as_dict()).size_mm == 32 * 2**0.5
    True
    """
    kind = record.get("kind") if isinstance(record, dict) else None
    if kind not in EXTENT_KINDS:
        known = ", ".join(EXTENT_KINDS)
        raise TranslucencyError(f"object: unknown extent {record!r}; expected one of {known}")
    return EXTENT_KINDS[kind].from_dict(record)
