r"""The lean: how the diffuse kernel of a point tilts toward the direction light enters by, and toward the
direction it leaves by — the angle-resolved extension of the paper's model.

The paper's model (and every data set acquired with normal beams) has no direction in or out:
:math:`R_d(x_i, x_o)` is what a beam entering along :math:`-n_i` gives.  A beam entering obliquely keeps
going the way it was refracted: its light comes out downstream of :math:`x_i` and less of it goes straight
through the body.  Measured on the virtual DISCO's oblique beams (``acquire mesh --incidence``), the
azimuthal Fourier content of :math:`R_d` about the beam is that of a von Mises lobe — first harmonic
0.5–1.6 of the mean, second 0.2–0.8, as :math:`2 I_1(k)/I_0(k)` and :math:`2 I_2(k)/I_0(k)` are
(docs/lean.md, "What the axes say about a model").  The lean is that lobe, written in 3D so that it also
covers pairs across a thin part:

.. math:: R_d(x_i, \omega_i \to x_o, \omega_o) = R_d(x_i, x_o)\;
          \frac{e^{\kappa_i\, \vec\ell(\omega_i, n_i) \cdot \hat d
                   - \lambda_i\, (\vec\ell \cdot n_i)\, r}}{Z_i(\omega_i)}\;
          \frac{e^{\kappa_o\, \vec\ell(\omega_o, n_o) \cdot (-\hat d)}}{N(\kappa_o, \hat d, n_o)},
          \qquad \hat d = \frac{x_o - x_i}{|x_o - x_i|},

with the **lean vector** :math:`\vec\ell(\omega, n) = \omega_t + n`: the refracted direction of the light
travelling in (:math:`\omega_t`, unit, into the body; for the exit, the camera's ray reversed) minus the
normal beam's :math:`-n`.  At normal incidence :math:`\vec\ell = 0` and the factor is 1: the data's
normal beams are the model's, bit for bit.  Obliquely, :math:`\vec\ell` points downstream along the
surface (length :math:`\sin\theta_t`) and out of the body (:math:`1 - \cos\theta_t` along :math:`n`), so
pairs across a thin part, :math:`\hat d \approx -n_i`, get :math:`e^{-\kappa (1-\cos\theta_t)}` — the
oblique beam's light stays nearer the lit surface, as the direction oracle measured.  The second
number, :math:`\lambda \ge 0` (mm⁻¹), shortens the kernel's reach by :math:`e^{-\lambda (1 - \cos\theta_t) r}`
(:math:`\vec\ell \cdot n = 1 - \cos\theta_t`, :math:`r = |x_o - x_i|`): an oblique beam scatters first
nearer the surface, so more of its light comes out near the entry (on the back-lit marble spot's data,
0.30 of a 60° beam's power within 1 mm against the normal beam's 0.26; ``benchmarks/lean_bands.py``).

:math:`\kappa \ge 0` (dimensionless) and λ are numbers per vertex and channel, fitted from the oblique beams
(:func:`translucency.fit.lean.fit_lean`); κ is meant for both sides, so the structure is reciprocal: swapping
:math:`(x_i, \omega_i) \leftrightarrow (x_o, \omega_o)` swaps the two exponentials.  The normalisations
keep energy: :math:`Z_i` makes the lean only redistribute the light of beam i among its receivers
(:math:`\sum_o A_o R_d\, e^{\ldots}/Z_i = \sum_o A_o R_d`), and :math:`N` makes the exit factor average to
1 over the exit hemisphere, cosine- (and Fresnel-) weighted, for every pair (:func:`exit_normalisation`),
so the exitance is the diffuse model's.  Being normalised per beam on one side and per pair on the other,
the two sides are reciprocal only to the extent that :math:`Z` and :math:`N` agree (stated by
``benchmarks/lean_reciprocity.py``).
"""

from __future__ import annotations

import numpy as np
from scipy.special import i0e, ive

from .boundary import fresnel_transmittance

#: the largest κ the fit considers: a lobe with e^{2 κ} between downstream and upstream
KAPPA_MAX = 8.0
#: the largest λ (mm⁻¹) the fit considers
LAMBDA_MAX = 1.0
#: Gauss–Legendre nodes of the exit normalisation's integral over μ_o
_MU_NODES = 24
#: what a command asked for ``--angles`` says of a model without a lean, in one line
NO_LEAN = "--angles: the model has no lean (fit data acquired with --incidence): paper's model"


def has_lean(model) -> bool:
    """Whether a fitted model carries the lean (κ, λ per incident point: ``measured["lean"]``)."""
    measured = getattr(model, "measured", None)
    return bool(measured) and "lean" in measured


def refracted(w: np.ndarray, n: np.ndarray, eta: float = 1.0) -> np.ndarray:
    r"""Unit direction of travel into the body, (…, 3), of light arriving from ``w`` (unit, toward the
    light or the camera) at unit normals ``n``: Snell's law with the relative index ``eta``,

    .. math:: \omega_t = -\frac{w}{\eta} + \Bigl(\frac{\cos\theta_i}{\eta} - \cos\theta_t\Bigr) n,
              \qquad \cos\theta_t = \sqrt{1 - (1 - \cos^2\theta_i)/\eta^2}.

    Directions below the horizon (:math:`\cos\theta_i \le 0`: no light enters there) are clamped to it.

    Examples
    --------
    >>> refracted(np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, 1.0]))  # a normal beam goes along −n
    array([ 0.,  0., -1.])
    >>> w = np.array([np.sin(np.pi / 3), 0.0, np.cos(np.pi / 3)])  # 60° in, index 1.5: 35.3° inside
    >>> t = refracted(w, np.array([0.0, 0.0, 1.0]), 1.5)
    >>> bool(np.isclose(np.degrees(np.arccos(-t[2])), 35.264, atol=1e-3))
    True
    """
    w, n = np.asarray(w, dtype=np.float64), np.asarray(n, dtype=np.float64)
    cos_i = np.clip(np.einsum("...k,...k->...", w, n)[..., None], 0.0, 1.0)
    cos_t = np.sqrt(np.maximum(1.0 - (1.0 - cos_i**2) / eta**2, 0.0))
    t = (cos_i / eta - cos_t) * n - w / eta
    return t / np.sqrt(np.einsum("...k,...k->...", t, t))[..., None]  # unit (a clamped one is not)


def lean_vector(w: np.ndarray, n: np.ndarray, eta: float = 1.0) -> np.ndarray:
    r"""The lean vector :math:`\vec\ell = \omega_t + n` (…, 3) of light arriving from ``w`` at normal ``n``
    (module docstring): 0 at normal incidence, :math:`|\vec\ell| = \sqrt{2(1 - \cos\theta_t)}`."""
    return refracted(w, n, eta) + np.asarray(n, dtype=np.float64)


def lean_exponent(kappa, lam, ell, d_hat, n, r):
    r"""The incidence lean's exponent
    :math:`\kappa\, \vec\ell \cdot \hat d - \lambda\, (\vec\ell \cdot n)\, r`
    (broadcast; the vectors on the last axis, κ and λ per channel broadcast against the result with a
    trailing channel axis by the caller).

    Examples
    --------
    >>> ell = lean_vector(np.array([np.sin(1.0), 0.0, np.cos(1.0)]), np.array([0.0, 0.0, 1.0]))
    >>> # 2 mm downstream along the surface: κ sin θ − λ (1 − cos θ) r
    >>> e = lean_exponent(1.2, 0.1, ell, np.array([-1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), 2.0)
    >>> bool(np.isclose(e, 1.2 * np.sin(1.0) - 0.1 * (1 - np.cos(1.0)) * 2.0))
    True
    """
    ell, d_hat, n = (np.asarray(x, dtype=np.float64) for x in (ell, d_hat, n))
    return kappa * np.sum(ell * d_hat, axis=-1) - lam * np.sum(ell * n, axis=-1) * np.asarray(r)


def exit_normalisation(kappa: np.ndarray, d: np.ndarray, n: np.ndarray, eta: float = 1.0) -> np.ndarray:
    r"""The exit factor's mean over the exit hemisphere, :math:`N(\kappa_o, \hat d', n_o)`, per pair.

    With :math:`\hat d' = (x_i - x_o)/r` split into its tangential length t and its normal part
    :math:`d_n` at :math:`x_o`, and the exit direction at polar :math:`\theta_o` (refracted inside to
    :math:`\theta'`), the azimuthal integral is a Bessel function:

    .. math:: N = \int_0^1 p(\mu_o)\; I_0\bigl(\kappa\, t \sin\theta'\bigr)\,
              e^{\kappa (1 - \cos\theta') d_n}\, d\mu_o, \qquad
              p(\mu) = \frac{\mu\, F_t(\mu)}{\int_0^1 \mu\, F_t(\mu)\, d\mu},

    the cosine- and Fresnel-weighted mean (p = 2μ where η = 1); N = 1 at κ = 0.

    Parameters
    ----------
    kappa : array_like, shape (M,) or (M, C)
        The exit vertex's κ per pair (and channel).
    d : array_like, shape (M, 3)
        Unit vectors from the exit vertex toward the incident vertex.
    n : array_like, shape (M, 3)
        The exit vertex's unit normal.
    eta : float
        Relative index of the boundary.

    Examples
    --------
    >>> d = np.array([[1.0, 0.0, 0.0]]); n = np.array([[0.0, 0.0, 1.0]])
    >>> round(float(exit_normalisation(np.array([0.0]), d, n)[0]), 12)  # no lean: the mean of 1
    1.0
    >>> from scipy.special import i1  # in the plane, η = 1: N = ∫ 2μ I0(κ √(1 − μ²)) dμ = 2 I1(κ) / κ
    >>> bool(np.isclose(exit_normalisation(np.array([2.0]), d, n)[0], 2 * i1(2.0) / 2.0))
    True
    """
    kappa = np.asarray(kappa, dtype=np.float64)
    d, n = np.asarray(d, dtype=np.float64), np.asarray(n, dtype=np.float64)
    d_n = np.sum(d * n, axis=-1)
    t = np.sqrt(np.maximum(1.0 - d_n**2, 0.0))
    x, wq = np.polynomial.legendre.leggauss(_MU_NODES)
    mu = 0.5 * (x + 1.0)  # external cosines on (0, 1)
    p = mu * fresnel_transmittance(mu, eta)
    p = 0.5 * wq * p / np.sum(0.5 * wq * p)  # quadrature weights of the normalised density
    sin_in = np.sqrt(1.0 - mu**2) / eta
    cos_in = np.sqrt(1.0 - sin_in**2)
    extra = (slice(None),) + (None,) * (kappa.ndim - 1)
    t, d_n = t[extra], d_n[extra]
    out = np.zeros(np.broadcast_shapes(kappa.shape, t.shape))
    for m in range(_MU_NODES):  # I0 via the scaled i0e: e^{x} i0e(x), one exponential with the rest
        x_b = kappa * t * sin_in[m]
        out += p[m] * i0e(x_b) * np.exp(x_b + kappa * (1.0 - cos_in[m]) * d_n)
    return out


def von_mises_harmonics(kappa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""The lobe :math:`e^{k \cos\varphi}`'s first two azimuthal harmonics over its mean,
    :math:`(2 I_1(k)/I_0(k),\; 2 I_2(k)/I_0(k))` — what ``benchmarks/angle_structure.py`` measures as
    c₁/c₀ and c₂/c₀ (k = κ sin θ_t for pairs in the tangent plane)."""
    k = np.asarray(kappa, dtype=np.float64)
    return 2.0 * ive(1, k) / ive(0, k), 2.0 * ive(2, k) / ive(0, k)
