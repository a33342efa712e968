"""The validation's narrow spot beam: its Mitsuba emitter, its irradiance on the plane z = 0, and photon
entries drawn from it.

A ``spot`` emitter of intensity :math:`I = 1` at height :math:`D` above the beam centre, pointing down,
cut off at :math:`\\theta_c = \\arctan(\\rho_b/D)` with Mitsuba's linear falloff from the beam width
:math:`\\tfrac34\\theta_c` to :math:`\\theta_c`.  The irradiance of the plane z = 0 is
:math:`E(\\rho) = I\\,f(\\theta)\\cos^3\\theta/D^2`; it is read from Mitsuba's own emitter (float32
included) by :func:`spot_profile`.  Units: mm, per unit intensity of the spot (W/sr).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError
from ..mitsuba import SPOT_BEAM_FRACTION, drjit, load_plugin, mitsuba, spot_dict
from ._checks import check_point, check_positive


@dataclass(frozen=True)
class SpotBeam:
    """A spot light at height ``distance_mm`` above ``centre_xy`` (mm), pointing straight down.

    ``radius_mm`` is the radius ρ_b = D tan θ_c of the lit disc on the plane z = 0.

    Examples
    --------
    >>> beam = SpotBeam((2.0, 2.0), radius_mm=0.5, distance_mm=100.0)
    >>> round(beam.cutoff_deg, 4), round(beam.beam_width_deg / beam.cutoff_deg, 2)   # atan(0.5/100); ¾ of it
    (0.2865, 0.75)
    >>> beam.emitter_dict()["type"]
    'spot'
    """

    centre_xy: tuple[float, float]
    radius_mm: float = 0.5
    distance_mm: float = 100.0

    def __post_init__(self):
        object.__setattr__(self, "centre_xy", check_point("beam centre", self.centre_xy))
        object.__setattr__(self, "radius_mm", check_positive("beam radius", self.radius_mm))
        object.__setattr__(self, "distance_mm", check_positive("beam distance", self.distance_mm))
        # float32 resolves cos θ only to ~6e-8, i.e. θ to ~3.5e-4 rad: keep the cutoff well above
        if self.cutoff_deg < 0.2 or self.cutoff_deg > 30.0:
            raise TranslucencyError(
                f"beam radius: {self.radius_mm} mm at {self.distance_mm} mm gives a cutoff of "
                f"{self.cutoff_deg:.3g} deg; keep it within [0.2, 30] deg (float32 angles)"
            )

    @property
    def cutoff_deg(self) -> float:
        """Cutoff angle θ_c of the spot, degrees."""
        return float(np.degrees(np.arctan(self.radius_mm / self.distance_mm)))

    @property
    def beam_width_deg(self) -> float:
        """Angle up to which the intensity is full (Mitsuba's convention, :data:`SPOT_BEAM_FRACTION`)."""
        return SPOT_BEAM_FRACTION * self.cutoff_deg

    def emitter_dict(self, intensity: float = 1.0) -> dict:
        """Mitsuba ``spot`` emitter description."""
        cx, cy = self.centre_xy
        return spot_dict(
            (cx, cy, self.distance_mm), (cx, cy, 0.0), self.cutoff_deg, intensity, up=(0.0, 1.0, 0.0)
        )


def spot_irradiance(beam: SpotBeam, rho_mm) -> np.ndarray:
    """Irradiance E(ρ) of the plane z = 0 per unit intensity, mm⁻², in float64.

    :math:`E = f(\\theta)\\cos^3\\theta / D^2` with :math:`\\tan\\theta = \\rho/D` and
    Mitsuba's falloff f: 1 up to the beam width θ_w, then linear in θ down
    to 0 at the cutoff θ_c.

    Examples
    --------
    >>> beam = SpotBeam((0.0, 0.0), radius_mm=0.5, distance_mm=100.0)
    >>> spot_irradiance(beam, [0.0, 0.6]) * 100.0**2   # 1/D² under the spot, 0 beyond its 0.5 mm disc
    array([1., 0.])
    """
    rho = np.asarray(rho_mm, dtype=np.float64)
    D = beam.distance_mm
    theta = np.arctan(rho / D)
    th_c, th_w = np.radians(beam.cutoff_deg), np.radians(beam.beam_width_deg)
    f = np.where(theta <= th_w, 1.0, np.clip((th_c - theta) / (th_c - th_w), 0.0, 1.0))
    return f * np.cos(theta) ** 3 / D**2


def spot_profile(beam: SpotBeam, n_radii: int = 8193) -> tuple[np.ndarray, np.ndarray]:
    """The spot's irradiance E(ρ) on z = 0 as Mitsuba evaluates it, on ``n_radii`` radii.

    Each value is the spot's ``sample_direction`` (I·f/r², float32 as
    rendered) times cos θ = D/r at a point of the plane; the radii run from 0
    to just past the cutoff radius.  Returns (rho (mm), E (mm⁻², float64)).

    Examples
    --------
    >>> beam = SpotBeam((2.0, 2.0), radius_mm=0.5, distance_mm=100.0)
    >>> rho, E = spot_profile(beam, n_radii=65)
    >>> round(float(E[0]) * 100.0**2, 6), float(E[-1])   # I/D² at the centre (float32), 0 past the cutoff
    (1.0, 0.0)
    >>> bool(np.abs(E - spot_irradiance(beam, rho)).max() < 0.02 / 100.0**2)   # the closed form, to float32
    True
    """
    mi, dr = mitsuba(), drjit()
    rho = np.linspace(0.0, beam.radius_mm * 1.02, int(n_radii))
    emitter = load_plugin(beam.emitter_dict())
    cx, cy = beam.centre_xy
    it = dr.zeros(mi.Interaction3f, len(rho))
    it.p = mi.Point3f(
        mi.Float((cx + rho).astype(np.float32)),
        mi.Float(np.full(len(rho), cy, np.float32)),
        mi.Float(np.zeros(len(rho), np.float32)),
    )
    _, value = emitter.sample_direction(it, mi.Point2f(0.5, 0.5))
    # distances and cosines in float64 from the points actually queried
    x = np.asarray(it.p.x, dtype=np.float64) - cx
    r = np.hypot(x, beam.distance_mm)
    E = np.asarray(value[0], dtype=np.float64) * beam.distance_mm / r
    return np.abs(x), E


def spot_power(rho: np.ndarray, E: np.ndarray) -> float:
    """Total power P = ∫ E dA = ∫ 2πρ E(ρ) dρ (trapezoid rule, float64), per unit intensity.

    Examples
    --------
    >>> rho = np.linspace(0.0, 1.0, 1001)
    >>> round(spot_power(rho, np.ones_like(rho)), 6)   # E = 1 on the unit disc: π
    3.141593
    """
    return float(np.trapezoid(2.0 * np.pi * rho * E, rho))


def sample_spot_entries(beam: SpotBeam, n: int, seed: int, profile=None) -> np.ndarray:
    """``n`` entry points (n, 2) in mm (float32) distributed as the irradiance E(ρ) of the plane z = 0.

    Inverse CDF of :math:`2\\pi\\rho E(\\rho)` (tabulated by :func:`spot_profile`,
    interpolated linearly) for ρ, and a uniform azimuth.

    Examples
    --------
    >>> beam = SpotBeam((2.0, 2.0), radius_mm=0.5, distance_mm=100.0)
    >>> rho = np.linspace(0.0, 0.51, 257)
    >>> xy = sample_spot_entries(beam, 1000, seed=0, profile=(rho, spot_irradiance(beam, rho)))
    >>> xy.shape, xy.dtype, bool(np.hypot(*(xy - 2.0).T).max() <= 0.5)   # all inside the lit disc
    ((1000, 2), dtype('float32'), True)
    """
    rho, E = profile if profile is not None else spot_profile(beam)
    dens = 2.0 * np.pi * rho * E
    end = (
        int(np.flatnonzero(dens > 0).max()) + 2
    )  # up to the first zero past the cutoff: a strictly rising CDF
    rho, dens = rho[:end], dens[:end]
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(rho))])
    cdf /= cdf[-1]
    # the inverse CDF on a fine uniform grid of u, then O(1) linear interpolation per sample
    m = 1 << 16
    inv = np.interp(np.linspace(0.0, 1.0, m + 1), cdf, rho)
    rng = np.random.default_rng(seed)
    u = rng.random(n) * m
    i = np.minimum(u.astype(np.int64), m - 1)
    f = u - i
    r = (inv[i] * (1.0 - f) + inv[i + 1] * f).astype(np.float32)
    phi = rng.random(n, dtype=np.float32) * np.float32(2.0 * np.pi)
    # float32 like the walk itself (µm-level rounding on a mm-sized slab); in place, as this runs per photon
    xy = np.empty((n, 2), np.float32)
    for k, (trig, c) in enumerate(((np.cos, beam.centre_xy[0]), (np.sin, beam.centre_xy[1]))):
        trig(phi, out=xy[:, k])
        xy[:, k] *= r
        xy[:, k] += np.float32(c)
    return xy
