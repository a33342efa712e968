r"""Physical guard rails: what each incident point's profile promises, against what physics allows.

For incident point :math:`x_i` with profile :math:`P_i` (α excluded):

* **total diffuse reflectance** :math:`\rho_i = \int P_i\, dA` per channel —
  for the exponential model :math:`2\pi \sum_k c_k / d_k^2` (closed form,
  :meth:`~translucency.model._base.ReflectanceModel.total_reflectance`) — is the
  fraction of the incident power that leaves diffusely; energy conservation
  demands :math:`\rho_i \le 1`;
* the **energy radius** :math:`r_{99.9}` (the radius holding 99.9 % of
  :math:`\rho_i`) must not exceed the object: light that enters a body leaves
  it within its own extent;
* α is a modulation of mean 1; the check reports its range.

:func:`check_physics` evaluates these per point; :func:`model_extent` gives the
size of the object a model describes (the diagonal of α's support).  The model
file records the result (``translucency info`` shows it, and a model that
breaks a bound is not called valid); the fitters and the renderer warn.

Units: mm, ρ dimensionless.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .alpha import PlanarAlpha

#: ρ may exceed 1 by this much before a point is flagged (float16 storage and quadrature round-off)
ALBEDO_TOLERANCE = 1e-3


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
        Extent of the object (diagonal of α's support), mm.
    over_albedo : ndarray of bool, shape (N,)
        ρ_i > 1 in some channel.
    beyond_object : ndarray of bool, shape (N,)
        r_99.9 larger than the object.
    """

    total: np.ndarray
    radius: np.ndarray
    size_mm: float
    over_albedo: np.ndarray
    beyond_object: np.ndarray

    @property
    def flagged(self) -> np.ndarray:
        """(N,) bool: the point breaks some bound."""
        return self.over_albedo | self.beyond_object

    @property
    def ok(self) -> bool:
        return not bool(self.flagged.any())

    def summary(self) -> dict:
        """JSON-friendly: counts, extremes and the indices of flagged points (stored in model files)."""
        return {
            "albedo_bound": 1.0,
            "size_mm": round(float(self.size_mm), 4),
            "max_total_reflectance": float(np.max(self.total)) if self.total.size else 0.0,
            "max_energy_radius_mm": float(np.max(self.radius)) if self.radius.size else 0.0,
            "over_albedo": np.flatnonzero(self.over_albedo).tolist(),
            "beyond_object": np.flatnonzero(self.beyond_object).tolist(),
        }

    def describe(self) -> str:
        """One line for a person: what breaks, how often, how badly."""
        n = len(self.radius)
        if self.ok:
            return (
                f"yes: total reflectance <= 1 (max {np.max(self.total):.3g}) and 99.9% energy radius within "
                f"the object (max {np.max(self.radius):.3g} of {self.size_mm:.3g} mm) at all {n} points"
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
                f"(99.9% energy radius up to {np.max(self.radius):.3g} mm on a {self.size_mm:.3g} mm object)"
            )
        return "no: " + "; ".join(parts)


def model_extent(model) -> float:
    """Size (mm) of the object a model describes: the diagonal of α's support (planar grid or vertices)."""
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
        The object's extent; default :func:`model_extent`.

    Returns
    -------
    PhysicsCheck

    Examples
    --------
    >>> import translucency as tl
    >>> alpha = tl.PlanarAlpha.uniform((40, 40), pitch=0.5)   # a 20 mm sample
    >>> ok = tl.ExponentialModel([[0.0, 0.0]], [[[[0.05]]]], [[[[-1.0]]]], alpha, s_g=[1.0], s_b=[1.0])
    >>> check_physics(ok).ok                    # 2π·0.05 = 0.31 of the light leaves within ~9 mm
    True
    >>> bright = tl.ExponentialModel([[0.0, 0.0]], [[[[5.0]]]], [[[[-1.0]]]], alpha, s_g=[1.0], s_b=[1.0])
    >>> print(check_physics(bright).describe())   # 2π·5 = 31 times the incident power
    no: 1 of 1 points reflect more than they receive (total reflectance up to 31.4 > 1)
    """
    size = model_extent(model) if size_mm is None else float(size_mm)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        total = np.asarray(model.total_reflectance(), dtype=np.float64)
        radius = np.asarray(model.energy_radius(0.999), dtype=np.float64)
    over = ~(total <= 1.0 + ALBEDO_TOLERANCE).all(axis=1)  # NaN counts as a violation
    beyond = ~(radius <= size) if size > 0 else np.zeros(len(radius), bool)
    return PhysicsCheck(total, radius, size, over, beyond)
