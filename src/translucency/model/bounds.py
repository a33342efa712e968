r"""Physical guard rails: what each incident point's profile promises, against what physics allows.

For incident point :math:`x_i` with profile :math:`P_i` (α excluded):

* **total diffuse reflectance** :math:`\rho_i = \int P_i\, dA` per channel —
  for the exponential model :math:`(2\pi/m) \sum_l \sum_k c_{lk} / d_{lk}^2`
  (closed form, :meth:`~translucency.model._base.ReflectanceModel.total_reflectance`;
  m = 1 isotropic; for m directions the blend's total, the mean of the
  directions' own totals) — is the fraction of the incident power that leaves
  diffusely; energy conservation demands :math:`\rho_i \le 1`.  Tolerance:
  :data:`ALBEDO_TOLERANCE` (float16 storage, quadrature round-off) and, for a
  model fitted to a photon tally of N photons per point, :data:`TALLY_SIGMAS`
  standard errors of a measured total at its noisiest (:math:`\sqrt{\rho(1-\rho)/N}
  \le 1/(2\sqrt N)`: 0.011 at N = 20,000).  A direction's own total is
  reported, not bounded: an anisotropic medium (fibres) sends more light along
  one direction than the mean, and only the blend's total is the energy that
  leaves the point;
* the **share beyond the object** :math:`b_i = \frac{1}{\rho_i} \int_0^{2\pi}
  \int_{R(\theta)}^\infty P_i\, r\, dr\, d\theta`, :math:`R(\theta)` the
  distance from :math:`x_i` to the object's edge (:mod:`translucency.model.extent`:
  the planar sample's rectangle, a mesh's diameter, none for a semi-infinite
  slab), closed form in r for sums of exponentials (:math:`c e^{-aR}(1 + aR)/a^2`
  per term), by each model's enclosed energy otherwise, both averaged over
  :data:`N_ANGLES` angles; it must not exceed :data:`BEYOND_TOLERANCE`;
* the **energy radius** :math:`r_{99.9}` (holding 99.9 % of :math:`\rho_i`)
  and α's range are reported: a slow tail holding 0.1 % of the energy beyond
  the object is not a wrong model.

:func:`check_physics` evaluates these per point; :func:`object_extent` gives the
object a model describes and :func:`model_extent` its size.  The model file
records the result (``translucency info`` shows it, and a model that breaks a
bound is not called valid); the fitters keep the totals (fit/_regularise.py) and
the renderer warns.

Units: mm, ρ dimensionless.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .alpha import PlanarAlpha
from .extent import Diameter, ObjectExtent

#: ρ may exceed 1 by this much before a point is flagged (float16 storage and quadrature round-off)
ALBEDO_TOLERANCE = 1e-3
#: and, for a model fitted to a photon tally, by this many standard errors of its measured total
TALLY_SIGMAS = 3.0
#: the largest share of a point's energy its profile may place beyond the object.  What a window
#: cannot see is extrapolated: the embedded demo data's 8 mm windows miss up to 35 % of the light a
#: photon tally counts (median 12 %: 1 − Σ window / total), and the fitters let a total exceed the
#: measured one by 20 % (fit.planar.TOTAL_TOLERANCE) — together about half.  A profile placing more
#: than half of its light beyond the object describes a larger one (a wrong rate: 99.9 % for
#: d = −0.004 mm⁻¹ on an 8 mm sample); every fit of the demo places at most a third there.
BEYOND_TOLERANCE = 0.5
#: angles of the quadrature over θ of the share beyond the object
N_ANGLES = 128


def albedo_bound(model) -> float:
    """The largest total reflectance ρ a point of ``model`` may have: 1 + :data:`ALBEDO_TOLERANCE`, plus
    :data:`TALLY_SIGMAS` × 1/(2√N) for a model fitted to a tally of N photons per point."""
    photons = getattr(model, "tally_photons", None)
    noise = TALLY_SIGMAS * 0.5 / math.sqrt(photons) if photons else 0.0
    return 1.0 + ALBEDO_TOLERANCE + noise


@dataclass
class PhysicsCheck:
    """Per-point physical bounds of a model (see the module docstring).

    Attributes
    ----------
    total : ndarray, shape (N, 3)
        Total diffuse reflectance ρ_i per channel.
    radius : ndarray, shape (N,)
        99.9 % energy radius, mm.
    size_mm : float
        Size of the object (its diameter; inf for a semi-infinite slab), mm.
    over_albedo : ndarray of bool, shape (N,)
        ρ_i > :attr:`albedo_bound` in some channel.
    beyond_object : ndarray of bool, shape (N,)
        More than :attr:`beyond_bound` of ρ_i beyond the object's edge in some channel.
    beyond : ndarray, shape (N,)
        The share of ρ_i beyond the object's edge (max over channels).
    albedo_bound : float
        The bound on ρ_i (1 plus the tolerances).
    beyond_bound : float
        The bound on the share beyond the object.
    extent : str
        The kind of object (:mod:`translucency.model.extent`).
    direction_total : ndarray, shape (N,), optional
        Anisotropic models: the largest of each point's directions' own totals (reported, not bounded).
    object : str, optional
        The object in words ("a 32 x 32 mm sample"); default from ``size_mm``.

    Examples
    --------
    >>> c = PhysicsCheck(total=np.array([[0.5, 0.5, 0.5], [1.2, 0.4, 0.3]]), radius=np.array([3.0, 4.0]),
    ...                  size_mm=20.0, over_albedo=np.array([False, True]),
    ...                  beyond_object=np.array([False, False]))
    >>> c.ok, c.flagged.tolist()
    (False, [False, True])
    >>> c.summary()["over_albedo"], c.summary()["max_total_reflectance"]   # the flagged points' indices
    ([1], 1.2)
    """

    total: np.ndarray
    radius: np.ndarray
    size_mm: float
    over_albedo: np.ndarray
    beyond_object: np.ndarray
    beyond: np.ndarray | None = None
    albedo_bound: float = 1.0 + ALBEDO_TOLERANCE
    beyond_bound: float = BEYOND_TOLERANCE
    extent: str = "rectangle"
    direction_total: np.ndarray | None = None
    object: str | None = None

    def __post_init__(self):
        if self.beyond is None:
            self.beyond = np.zeros(len(self.radius))

    @property
    def flagged(self) -> np.ndarray:
        """(N,) bool: the point breaks some bound."""
        return self.over_albedo | self.beyond_object

    @property
    def ok(self) -> bool:
        return not bool(self.flagged.any())

    def summary(self) -> dict:
        """JSON-friendly: counts, extremes, the bounds and the indices of flagged points (stored in model
        files)."""
        out = {
            "albedo_bound": 1.0,
            "albedo_tolerance": round(float(self.albedo_bound) - 1.0, 6),
            # null for a semi-infinite slab: the header stays strict JSON (no Infinity) for every Zarr reader
            "size_mm": round(float(self.size_mm), 4) if math.isfinite(self.size_mm) else None,
            "extent": self.extent,
            "object": self._object(),
            "max_total_reflectance": float(np.max(self.total)) if self.total.size else 0.0,
            "max_energy_radius_mm": float(np.max(self.radius)) if self.radius.size else 0.0,
            "beyond_object_bound": float(self.beyond_bound),
            "max_beyond_object": float(np.max(self.beyond)) if self.beyond.size else 0.0,
            "over_albedo": np.flatnonzero(self.over_albedo).tolist(),
            "beyond_object": np.flatnonzero(self.beyond_object).tolist(),
        }
        if self.direction_total is not None and self.direction_total.size:
            out["max_direction_total"] = float(np.max(self.direction_total))
        return out

    def _object(self) -> str:
        if self.object:
            return self.object
        if not math.isfinite(self.size_mm):
            return "a semi-infinite slab"
        return f"a {self.size_mm:.3g} mm object"

    def describe(self) -> str:
        """One line for a person: what breaks, how often, how badly."""
        n = len(self.radius)
        if self.ok:
            beyond = (
                "no object edge (a semi-infinite slab)"
                if not math.isfinite(self.size_mm)
                else f"at most {100 * np.max(self.beyond):.2g}% of a point's energy beyond the object "
                f"(bound {100 * self.beyond_bound:.0f}%)"
            )
            return (
                f"yes: total reflectance <= {self.albedo_bound:.4g} (max {np.max(self.total):.3g}) and "
                f"{beyond} at all {n} points; 99.9% energy radius up to {np.max(self.radius):.3g} mm on "
                f"{self._object()}"
            )
        parts = []
        if self.over_albedo.any():
            parts.append(
                f"{int(self.over_albedo.sum())} of {n} points reflect more than they receive "
                f"(total reflectance up to {np.max(self.total):.3g} > 1)"
            )
        if self.beyond_object.any():
            parts.append(
                f"{int(self.beyond_object.sum())} of {n} points spread light beyond the object "
                f"(up to {100 * np.max(self.beyond):.3g}% of their energy, bound "
                f"{100 * self.beyond_bound:.0f}%, on {self._object()}; 99.9% energy radius up to "
                f"{np.max(self.radius):.3g} mm)"
            )
        return "no: " + "; ".join(parts)


def object_extent(model) -> ObjectExtent:
    """The object ``model`` describes: its recorded :attr:`~ReflectanceModel.extent` (a fitted planar
    sample's rectangle, a semi-infinite slab), else an object the size of α's support: the diagonal of a
    planar α's grid (the sample is at least as large as its windows) or of a mesh's bounding box.

    Examples
    --------
    >>> from translucency.model import BurleyModel, PlanarAlpha, Rectangle
    >>> m = BurleyModel([[0.0, 0.0]], [[0.8] * 3], [[2.0] * 3], PlanarAlpha.uniform((30, 40), pitch=0.1))
    >>> object_extent(m)   # nothing recorded: α's 3 x 4 mm grid, 5 mm across
    <Diameter {'kind': 'diameter', 'size_mm': 5.0}>
    >>> m.extent = Rectangle((0, 0), (32, 32))   # what a fitter records: the sample's top face
    >>> object_extent(m).describe()
    'a 32 x 32 mm sample'
    """
    if getattr(model, "extent", None) is not None:
        return model.extent
    size = model_extent(model)
    return Diameter(size if size > 0 else 1e-9)


def model_extent(model) -> float:
    """Size (mm) of the object a model describes: its recorded extent's diameter, else the diagonal of
    α's support (planar grid or vertices).

    Examples
    --------
    >>> from translucency.model import BurleyModel, VertexAlpha
    >>> cube = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [0, 0, 1]], dtype=float)
    >>> m = BurleyModel(cube[:1], [[0.8] * 3], [[2.0] * 3], VertexAlpha.uniform(cube), frame=np.eye(3)[None])
    >>> model_extent(m)   # the bounding box's diagonal: √(2² + 2² + 1²) mm
    3.0
    """

    if getattr(model, "extent", None) is not None:
        return model.extent.size_mm
    alpha = model.alpha
    if isinstance(alpha, PlanarAlpha):
        return float(np.hypot(*alpha.shape) * alpha.pitch)
    v = np.asarray(alpha.vertices, dtype=np.float64)
    return float(np.linalg.norm(np.ptp(v, axis=0))) if len(v) else 0.0


def check_physics(model, *, size_mm: float | None = None) -> PhysicsCheck:
    """Check every incident point of ``model`` against the physical bounds.

    Parameters
    ----------
    model : ReflectanceModel
    size_mm : float, optional
        The object's diameter, mm; default: the object the model records (:func:`object_extent`).

    Returns
    -------
    PhysicsCheck

    Examples
    --------
    >>> import translucency as tl
    >>> alpha = tl.PlanarAlpha.uniform((40, 40), pitch=0.5)   # a 20 mm sample
    >>> ok = tl.ExponentialModel([[0.0, 0.0]], [[[[0.05]]]], [[[[-1.0]]]], alpha, s_g=[1.0], s_b=[1.0])
    >>> check_physics(ok).ok                    # 2π·0.05 = 0.31 of the light, 0.5 % beyond 20 mm
    True
    >>> bright = tl.ExponentialModel([[0.0, 0.0]], [[[[5.0]]]], [[[[-1.0]]]], alpha, s_g=[1.0], s_b=[1.0])
    >>> print(check_physics(bright).describe())   # 2π·5 = 31 times the incident power
    no: 1 of 1 points reflect more than they receive (total reflectance up to 31.4 > 1)
    >>> # 0.31 of the light again, but with a 100 mm fall-off: most of it beyond the sample
    >>> slow = tl.ExponentialModel([[0.0, 0.0]], [[[[5e-6]]]], [[[[-0.01]]]], alpha, s_g=[1.0], s_b=[1.0])
    >>> print(check_physics(slow).describe())   # doctest: +ELLIPSIS
    no: 1 of 1 points spread light beyond the object (up to 96.7% of their energy, bound 50%, ...
    """
    extent = object_extent(model) if size_mm is None else Diameter(size_mm)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        total = np.asarray(model.total_reflectance(), dtype=np.float64)
        radius = np.asarray(model.energy_radius(0.999), dtype=np.float64)
        if math.isfinite(extent.size_mm):
            theta = 2 * np.pi * (np.arange(N_ANGLES) + 0.5) / N_ANGLES
            out = np.asarray(model.energy_beyond(extent.distance(model.x_i, theta)), dtype=np.float64)
            share = np.max(np.divide(out, total, out=np.zeros_like(out), where=total > 0), axis=1)
        else:  # a semi-infinite slab: no edge to lie beyond
            share = np.zeros(len(radius))
    bound = albedo_bound(model)
    over = ~(total <= bound).all(axis=1)  # NaN counts as a violation
    beyond = ~(share <= BEYOND_TOLERANCE)
    own = model.direction_totals().max(axis=(1, 2)) if getattr(model, "n_directions", 1) > 1 else None
    return PhysicsCheck(total, radius, extent.size_mm, over, beyond, share, bound, BEYOND_TOLERANCE,
                        extent.kind, own, extent.describe())  # fmt: skip
