r"""The directional dipole of Frisvad, Hachisuka and Kjeldsen (2014), at normal incidence on a plane.

The paper's BSSRDF for light refracted into direction :math:`\vec\omega_{12}` at
:math:`\vec x_i` and leaving at :math:`\vec x_o` is
:math:`S_d = S_d'(\vec x_o - \vec x_i, \vec\omega_{12}, d_r) - S_d'(\vec x_o - \vec x_v, \vec\omega_v, d_v)`
(clamped at 0) with

.. math::

   S_d'(\vec x, \vec\omega, r) = \frac{1}{1 - 2C_1(1/\eta)}\frac{1}{4\pi^2}\frac{e^{-\sigma_{tr} r}}{r^3}
     \Bigl[C_\phi\Bigl(\frac{r^2}{D} + 3(1 + \sigma_{tr} r)\,\vec x\cdot\vec\omega\Bigr)
     - C_E\Bigl(3D(1 + \sigma_{tr} r)\,\vec\omega\cdot\vec n_o
       - \Bigl((1 + \sigma_{tr} r) + \frac{3D}{r^2}\bigl(3(1 + \sigma_{tr} r) + (\sigma_{tr} r)^2\bigr)
         \vec x\cdot\vec\omega\Bigr)\vec x\cdot\vec n_o\Bigr)\Bigr],

:math:`D = 1/(3\sigma_t')` (as in the authors' sample code), :math:`\sigma_{tr} = \sqrt{\sigma_a/D}`,
:math:`d_e = 2.131\,D/\sqrt{\alpha'}`, :math:`A = (1 - C_E)/(2C_\phi)`,
:math:`C_\phi = (1 - 2C_1)/4`, :math:`C_E = (1 - 3C_2)/2` from the Fresnel
moments of internal reflection (:func:`translucency.model.pbd.fresnel_moment`),
the virtual source :math:`\vec x_v = \vec x_i + 2Ad_e\vec n_i^*` and the
real-source distance :math:`d_r^2 = r^2 + D\mu_0(D\mu_0 - 2d_e\cos\beta)`.

**Reduced to normal incidence on a plane** (what a planar scan measures): the
light refracts straight down, :math:`\vec\omega_{12} = -\vec n`; the modified
normal :math:`\vec n_i^*` is :math:`\vec n`; :math:`\vec\omega_v = \vec n`;
:math:`\mu_0 = 1`; :math:`\cos\beta = -r/\sqrt{r^2 + d_e^2}`; :math:`\vec x_o - \vec x_i`
lies in the plane, so :math:`\vec x\cdot\vec\omega_{12} = \vec x\cdot\vec n_o = 0`
for the real source, and :math:`\vec x\cdot\vec\omega_v = \vec x\cdot\vec n_o = -h`
with :math:`h = 2Ad_e` for the virtual one.  With :math:`d_r = \sqrt{r^2 + D^2 + 2Dd_e r/\sqrt{r^2 + d_e^2}}`,
:math:`d_v = \sqrt{r^2 + h^2}`, :math:`s = 1 + \sigma_{tr} d`:

.. math::

   R_d(r) = \frac{1}{4\pi}\Bigl[\frac{e^{-\sigma_{tr} d_r}}{d_r^3}
       \Bigl(C_\phi\frac{d_r^2}{D} + 3C_E D s_r\Bigr)
     - \frac{e^{-\sigma_{tr} d_v}}{d_v^3}\Bigl(C_\phi\Bigl(\frac{d_v^2}{D} - 3h s_v\Bigr)
       - C_E\Bigl(3Ds_v + h s_v
         - \frac{3Dh^2}{d_v^2}\bigl(3s_v + (\sigma_{tr}d_v)^2\bigr)\Bigr)\Bigr)\Bigr]_+ ,

the diffuse exitance per unit power entering,
:math:`\int S_d\,T_{21}\cos\theta_o\,d\omega_o = \pi\bigl(1 - 2C_1(1/\eta)\bigr)S_d`, whose
factor cancels the paper's normalisation :math:`1/(1 - 2C_1(1/\eta))`.  The entering
Fresnel transmittance is left out, as for the other models (α takes such scales).
The profile is rotationally symmetric at normal incidence: the directional
terms live only in the depth of the sources.
"""

from __future__ import annotations

import numpy as np

from .pbd import _TabulatedRadialModel, fresnel_moment

#: Frisvad et al.'s extrapolation distance d_e = DE_FACTOR · D / √α'
DE_FACTOR = 2.131


def directional_dipole_coefficients(sigma_a, sigma_s_prime, eta) -> dict:
    """D, σ_tr, d_e, h = 2 A d_e (mm or mm⁻¹), C_φ, C_E and A of the directional dipole.

    Examples
    --------
    >>> k = directional_dipole_coefficients(0.0, 1.0, 1.0)   # index-matched: A = 1
    >>> round(float(k["A"]), 6), round(float(k["d_e"]), 4)
    (1.0, 0.7103)
    """
    sigma_a = np.asarray(sigma_a, dtype=np.float64)
    sigma_s_prime = np.asarray(sigma_s_prime, dtype=np.float64)
    sigma_t = sigma_a + sigma_s_prime
    D = 1.0 / (3.0 * sigma_t)
    C1, C2 = fresnel_moment(1, float(eta)), fresnel_moment(2, float(eta))
    C_phi, C_E = 0.25 * (1.0 - 2.0 * C1), 0.5 * (1.0 - 3.0 * C2)
    A = (1.0 - C_E) / (2.0 * C_phi)
    d_e = DE_FACTOR * D / np.sqrt(sigma_s_prime / sigma_t)
    return {"D": D, "sigma_tr": np.sqrt(sigma_a / D), "d_e": d_e, "h": 2.0 * A * d_e,
            "C_phi": C_phi, "C_E": C_E, "A": A}  # fmt: skip


def directional_dipole_R_d(r, sigma_a, sigma_s_prime, eta) -> np.ndarray:
    """Directional-dipole exitance :math:`R_d(r)` in mm⁻² at normal incidence, distance r (mm).

    Parameters broadcast against each other.

    Examples
    --------
    >>> round(float(directional_dipole_R_d(1.0, 0.0021, 2.19, 1.3)), 4)   # marble, red, r = 1 mm
    0.0519
    """
    k = directional_dipole_coefficients(sigma_a, sigma_s_prime, eta)
    r = np.asarray(r, dtype=np.float64)
    D, sig, d_e, h, C_phi, C_E = (k[n] for n in ("D", "sigma_tr", "d_e", "h", "C_phi", "C_E"))
    # the real source: its distance (mm) with the paper's shift of D μ₀ along the refracted ray
    d_r = np.sqrt(r**2 + D**2 + 2.0 * D * d_e * r / np.sqrt(r**2 + d_e**2))
    s_r = 1.0 + sig * d_r
    real = np.exp(-sig * d_r) / d_r**3 * (C_phi * d_r**2 / D + 3.0 * C_E * D * s_r)
    # the virtual source at height h = 2 A d_e above x_i, pointing out of the medium
    d_v = np.sqrt(r**2 + h**2)
    s_v = 1.0 + sig * d_v
    flux = 3.0 * D * s_v + h * s_v - 3.0 * D * h**2 / d_v**2 * (3.0 * s_v + (sig * d_v) ** 2)
    virtual = np.exp(-sig * d_v) / d_v**3 * (C_phi * (d_v**2 / D - 3.0 * h * s_v) - C_E * flux)
    return np.maximum(real - virtual, 0.0) / (4.0 * np.pi)


class DirectionalDipoleModel(_TabulatedRadialModel):
    """The directional dipole at normal incidence per incident point (σ_a, σ_s' per channel), with α.

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

    Examples
    --------
    >>> from translucency.model import PlanarAlpha
    >>> m = DirectionalDipoleModel([[0.0, 0.0]], [[0.01] * 3], [[1.0] * 3], 1.3,
    ...                            PlanarAlpha(np.ones((2, 2)), (-1.0, -1.0), 1.0))
    >>> round(float(m.profile(np.array(0), np.array(1.0), np.array(0.0))[0]), 4)
    0.0349
    """

    kind = "ddipole"

    def _R(self, r, sigma_a, sigma_s_prime):
        return directional_dipole_R_d(r, sigma_a, sigma_s_prime, self.eta)
