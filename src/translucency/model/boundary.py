r"""The object's boundary seen from outside: Fresnel transmittance and the exit's angular law.

Light leaving a scattering medium through a smooth dielectric boundary of relative index η has, in the
diffusion approximation, the radiance

.. math:: L(\theta_o) = M\, \frac{F_t(\theta_o)}{\pi\,(1 - F_{dr,e})}

for the exitance M (W/mm²), normalised so that :math:`\int L \cos\theta_o\, d\omega = M`.  The
renderer draws exitance with this law (:mod:`translucency.transport.relight`) and an object rig's
importer inverts it (:mod:`translucency.rig.object.exit_law`): one home for both.
"""

from __future__ import annotations

import numpy as np

from ..mitsuba import mitsuba


def fresnel_transmittance(cos_theta, eta: float) -> np.ndarray:
    r"""Unpolarised Fresnel transmittance :math:`1 - F(\cos\theta, \eta)` from outside (Mitsuba's term)."""
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    if eta == 1.0:
        return np.ones_like(cos_theta)
    mi = mitsuba()
    c = np.clip(cos_theta, 0.0, 1.0).ravel()
    F = np.asarray(mi.fresnel(mi.Float(c.astype(np.float32)), mi.Float(float(eta)))[0], dtype=np.float64)
    return (1.0 - F).reshape(cos_theta.shape)


def diffuse_transmittance(eta: float, n: int = 512) -> float:
    r""":math:`1 - F_{dr,e} = 2\int_0^1 F_t(\mu)\, \mu\, d\mu`: the cosine-weighted transmittance
    from outside (midpoint rule)."""
    mu = (np.arange(n) + 0.5) / n
    return float(2.0 * np.mean(fresnel_transmittance(mu, eta) * mu))


def exit_factor(cos_theta, eta: float) -> np.ndarray:
    r""":math:`\pi L(\theta_o)/M = F_t(\theta_o)/(1 - F_{dr,e})`: the radiance seen at ``cos_theta``
    relative to a Lambertian exit of the same exitance (1 where η = 1: the boundary adds no angular law)."""
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    if eta == 1.0:
        return np.ones_like(cos_theta)
    return fresnel_transmittance(cos_theta, eta) / diffuse_transmittance(eta)
