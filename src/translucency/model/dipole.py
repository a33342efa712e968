r"""The dipole diffusion model of Jensen, Marschner, Levoy and Hanrahan (2001).

For a semi-infinite homogeneous medium with absorption :math:`\sigma_a`,
reduced scattering :math:`\sigma_s'` (both mm⁻¹) and relative index
:math:`\eta`, light entering at :math:`\vec x_i` leaves at distance r with

.. math::

   R_d(r) = \frac{\alpha'}{4\pi}\Bigl[
       z_r (\sigma_{tr} d_r + 1)\frac{e^{-\sigma_{tr} d_r}}{d_r^3}
     + z_v (\sigma_{tr} d_v + 1)\frac{e^{-\sigma_{tr} d_v}}{d_v^3}\Bigr],
   \qquad d_{r,v} = \sqrt{r^2 + z_{r,v}^2}

with :math:`\sigma_t' = \sigma_a + \sigma_s'`, :math:`\alpha' = \sigma_s'/\sigma_t'`,
:math:`D = 1/(3\sigma_t')`, :math:`\sigma_{tr} = \sqrt{3\sigma_a\sigma_t'}`,
:math:`z_r = 1/\sigma_t'`, :math:`z_v = z_r + 4AD`,
:math:`A = (1 + F_{dr})/(1 - F_{dr})` and
:math:`F_{dr} = -1.440/\eta^2 + 0.710/\eta + 0.668 + 0.0636\,\eta`.

Because :math:`\frac{d}{dd}\bigl(-e^{-\sigma d}/d\bigr) = (\sigma d + 1)e^{-\sigma d}/d^2`,
the energy inside a disk of radius R is closed form,

.. math::

   \int_0^R 2\pi r R_d\, dr = \frac{\alpha'}{2}\sum_{z \in \{z_r, z_v\}}
       \Bigl(e^{-\sigma_{tr} z} - z\,\frac{e^{-\sigma_{tr} d(R)}}{d(R)}\Bigr),

whose limit is Jensen's total diffuse reflectance
:math:`\frac{\alpha'}{2}\bigl(1 + e^{-\frac43 A\sqrt{3(1-\alpha')}}\bigr)e^{-\sqrt{3(1-\alpha')}}`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._base import MediumStorage, ReflectanceModel, medium_parameters
from .alpha import Modulation


def fresnel_diffuse_reflectance(eta) -> np.ndarray:
    """Jensen's polynomial fit :math:`F_{dr}(\\eta)` of the diffuse Fresnel reflectance.

    Examples
    --------
    >>> round(float(fresnel_diffuse_reflectance(1.0)), 4)   # no index mismatch: (almost) no reflection
    0.0016
    >>> round(float(fresnel_diffuse_reflectance(1.3)), 4)   # Jensen's materials
    0.4448
    """
    eta = np.asarray(eta, dtype=np.float64)
    return -1.440 / eta**2 + 0.710 / eta + 0.668 + 0.0636 * eta


@dataclass(frozen=True)
class DipoleCoefficients:
    """Derived dipole quantities (lengths in mm, coefficients in mm⁻¹)."""

    sigma_t_prime: np.ndarray
    alpha_prime: np.ndarray
    D: np.ndarray
    sigma_tr: np.ndarray
    A: np.ndarray
    z_r: np.ndarray
    z_v: np.ndarray


def dipole_coefficients(sigma_a, sigma_s_prime, eta) -> DipoleCoefficients:
    """Compute σ_t', α', D, σ_tr, A, z_r and z_v from σ_a, σ_s' (mm⁻¹) and η.

    Examples
    --------
    >>> k = dipole_coefficients(0.0021, 2.19, 1.3)   # marble, red (Jensen 2001)
    >>> round(float(k.z_r), 4)   # 1 / σ_t'
    0.4562
    """
    sigma_a = np.asarray(sigma_a, dtype=np.float64)
    sigma_s_prime = np.asarray(sigma_s_prime, dtype=np.float64)
    sigma_t_prime = sigma_a + sigma_s_prime
    alpha_prime = sigma_s_prime / sigma_t_prime
    D = 1.0 / (3.0 * sigma_t_prime)
    sigma_tr = np.sqrt(3.0 * sigma_a * sigma_t_prime)
    F_dr = fresnel_diffuse_reflectance(eta)
    A = (1.0 + F_dr) / (1.0 - F_dr)
    z_r = 1.0 / sigma_t_prime
    z_v = z_r + 4.0 * A * D
    return DipoleCoefficients(sigma_t_prime, alpha_prime, D, sigma_tr, A * np.ones_like(z_r), z_r, z_v)


def dipole_R_d(r, sigma_a, sigma_s_prime, eta) -> np.ndarray:
    """Dipole diffuse reflectance :math:`R_d(r)` in mm⁻² at distance r (mm).

    Parameters broadcast against each other.

    Examples
    --------
    >>> round(float(dipole_R_d(1.0, 0.0021, 2.19, 1.3)), 4)   # marble, red, r = 1 mm
    0.0405
    """
    k = dipole_coefficients(sigma_a, sigma_s_prime, eta)
    r = np.asarray(r, dtype=np.float64)
    d_r = np.sqrt(r**2 + k.z_r**2)
    d_v = np.sqrt(r**2 + k.z_v**2)
    real = k.z_r * (k.sigma_tr * d_r + 1.0) * np.exp(-k.sigma_tr * d_r) / d_r**3
    virtual = k.z_v * (k.sigma_tr * d_v + 1.0) * np.exp(-k.sigma_tr * d_v) / d_v**3
    return k.alpha_prime / (4.0 * np.pi) * (real + virtual)


def dipole_energy_within(radius, sigma_a, sigma_s_prime, eta) -> np.ndarray:
    """Closed-form :math:`\\int_0^R 2\\pi r R_d(r)\\,dr` (dimensionless); R may be ``inf``.

    Examples
    --------
    >>> marble_red = (0.0021, 2.19, 1.3)   # σ_a, σ_s' (mm⁻¹), η
    >>> round(float(dipole_energy_within(1.0, *marble_red)), 4)   # within 1 mm
    0.3409
    >>> # R = ∞ is Jensen's total diffuse reflectance
    >>> bool(np.isclose(dipole_energy_within(np.inf, *marble_red), dipole_total_reflectance(*marble_red)))
    True
    """
    k = dipole_coefficients(sigma_a, sigma_s_prime, eta)
    radius = np.asarray(radius, dtype=np.float64)
    out = 0.0
    for z in (k.z_r, k.z_v):
        d = np.sqrt(radius**2 + z**2)
        tail = np.where(np.isinf(d), 0.0, z * np.exp(-k.sigma_tr * np.where(np.isinf(d), 0.0, d)) / d)
        out = out + np.exp(-k.sigma_tr * z) - tail
    return 0.5 * k.alpha_prime * out


def dipole_total_reflectance(sigma_a, sigma_s_prime, eta) -> np.ndarray:
    """Jensen's closed form of the total diffuse reflectance :math:`R_d` (dimensionless).

    Examples
    --------
    >>> round(float(dipole_total_reflectance(0.0041, 2.62, 1.3)), 2)   # marble, green
    0.83
    """
    k = dipole_coefficients(sigma_a, sigma_s_prime, eta)
    root = np.sqrt(3.0 * (1.0 - k.alpha_prime))
    return 0.5 * k.alpha_prime * (1.0 + np.exp(-4.0 / 3.0 * k.A * root)) * np.exp(-root)


class DipoleModel(MediumStorage, ReflectanceModel):
    """Jensen's dipole with per-:math:`\\vec x_i` coefficients and a global modulation texture.

    This is the approach the paper replaces: each incident point gets its own
    :math:`\\sigma_a, \\sigma_s'` (RGB, mm⁻¹); :math:`\\eta` is global.

    Parameters
    ----------
    x_i : array_like, shape (N, 2) or (N, 3)
        Incident points in mm.
    sigma_a, sigma_s_prime : array_like, shape (N, 3)
        Absorption and reduced scattering per point and channel, mm⁻¹.
    eta : float
        Relative index of refraction of the boundary.
    alpha : PlanarAlpha or VertexAlpha
        Modulation texture.
    frame : array_like, optional
        Tangent frames for mesh models.

    Examples
    --------
    >>> from translucency.model import DipoleModel, PlanarAlpha, material
    >>> marble = material("marble")
    >>> m = DipoleModel([[0.0, 0.0]], marble.sigma_a[None], marble.sigma_s_prime[None], marble.eta,
    ...                 PlanarAlpha.uniform((8, 8), (-2, -2), 0.5))
    >>> m.total_reflectance().round(3)   # Jensen's closed form per channel (RGB)
    array([[0.867, 0.834, 0.801]])
    >>> m.R_d([0], [[1.0, 0.0]]).round(4)   # mm⁻², 1 mm from x_i (α = 1)
    array([[0.0405, 0.041 , 0.0408]])
    """

    kind = "dipole"

    def __init__(self, x_i, sigma_a, sigma_s_prime, eta: float, alpha: Modulation, *, frame=None):
        super().__init__(x_i, alpha, frame)
        self.sigma_a, self.sigma_s_prime, self.eta = medium_parameters(
            self.n_points, sigma_a, sigma_s_prime, eta
        )

    def profile(self, i, r, theta) -> np.ndarray:
        """Dipole :math:`R_d(r)` per channel (rotationally symmetric: θ is unused)."""
        return dipole_R_d(r[..., None], self.sigma_a[i], self.sigma_s_prime[i], self.eta)

    def energy_within(self, i, radius) -> np.ndarray:
        i = np.asarray(i)
        radius = np.broadcast_to(np.asarray(radius, dtype=np.float64), i.shape)
        return dipole_energy_within(radius[..., None], self.sigma_a[i], self.sigma_s_prime[i], self.eta)

    def total_reflectance(self) -> np.ndarray:
        return dipole_total_reflectance(self.sigma_a, self.sigma_s_prime, self.eta)
