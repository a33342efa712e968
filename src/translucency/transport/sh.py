r"""Real spherical harmonics: the light basis of precomputed radiance transfer.

Directions are unit vectors in the object's frame (mm, +z up), :math:`\theta` from +z and
:math:`\varphi` from +x towards +y.  The orthonormal real basis, band :math:`l \ge 0`,
:math:`-l \le m \le l`, index :math:`k = l(l + 1) + m`:

.. math::

    Y_l^m = \begin{cases}
        \sqrt2\, K_l^m \cos(m\varphi)\, P_l^m(\cos\theta) & m > 0 \\
        K_l^0\, P_l^0(\cos\theta) & m = 0 \\
        \sqrt2\, K_l^{|m|} \sin(|m|\varphi)\, P_l^{|m|}(\cos\theta) & m < 0
    \end{cases}, \qquad
    K_l^m = \sqrt{\frac{2l + 1}{4\pi} \frac{(l - m)!}{(l + m)!}},

with the associated Legendre functions :math:`P_l^m` without the Condon–Shortley phase, by the
usual recurrences (the page's shader code evaluates the same recurrence, ``viewer.js``).  A light
:math:`L(\omega)` has coefficients :math:`L_k = \int L\, Y_k\, d\omega`; a directional light of
irradiance E arriving from :math:`\omega_l` has :math:`L_k = E\, Y_k(\omega_l)`.  Turning a light about
+z by :math:`\gamma` mixes only :math:`(l, m)` with :math:`(l, -m)` (:func:`rotate_z`).
"""

from __future__ import annotations

import math

import numpy as np


def n_coefficients(bands: int) -> int:
    """Coefficients of the first ``bands`` bands (l < bands): bands²."""
    return bands * bands


def basis(directions, bands: int) -> np.ndarray:
    r"""The real SH :math:`Y_k(\omega)` of the first ``bands`` bands at unit ``directions`` (..., 3).

    Returns (..., bands²).

    Examples
    --------
    >>> y = basis(np.array([0.0, 0.0, 1.0]), 2)  # the pole: only m = 0 is non-zero
    >>> np.round(y * np.sqrt(4 * np.pi), 4).tolist()
    [1.0, 0.0, 1.7321, 0.0]
    """
    w = np.asarray(directions, dtype=np.float64)
    x, y, z = w[..., 0], w[..., 1], np.clip(w[..., 2], -1.0, 1.0)
    phi = np.arctan2(y, x)
    P = _legendre(z, bands)
    out = np.empty(w.shape[:-1] + (bands * bands,))
    for l in range(bands):
        for m in range(l + 1):
            K = math.sqrt((2 * l + 1) / (4 * math.pi) * math.factorial(l - m) / math.factorial(l + m))
            if m == 0:
                out[..., l * (l + 1)] = K * P[(l, 0)]
            else:
                out[..., l * (l + 1) + m] = math.sqrt(2.0) * K * np.cos(m * phi) * P[(l, m)]
                out[..., l * (l + 1) - m] = math.sqrt(2.0) * K * np.sin(m * phi) * P[(l, m)]
    return out


def _legendre(z: np.ndarray, bands: int) -> dict:
    r""":math:`P_l^m(z)` for l < bands, 0 ≤ m ≤ l, without the Condon–Shortley phase:
    :math:`P_m^m = (2m - 1)!!\,(1 - z^2)^{m/2}`, :math:`P_{m+1}^m = (2m + 1) z P_m^m`,
    :math:`(l - m) P_l^m = (2l - 1) z P_{l-1}^m - (l + m - 1) P_{l-2}^m`."""
    s = np.sqrt(np.maximum(1.0 - z * z, 0.0))
    P = {}
    pmm = np.ones_like(z)
    for m in range(bands):
        if m > 0:
            pmm = pmm * (2 * m - 1) * s
        P[(m, m)] = pmm
        if m + 1 < bands:
            P[(m + 1, m)] = (2 * m + 1) * z * pmm
        for l in range(m + 2, bands):
            P[(l, m)] = ((2 * l - 1) * z * P[(l - 1, m)] - (l + m - 1) * P[(l - 2, m)]) / (l - m)
    return P


def rotate_z(coefficients, gamma: float) -> np.ndarray:
    r"""The coefficients (K, ...) of a light turned about +z by ``gamma`` radians:
    :math:`L'(\varphi) = L(\varphi - \gamma)`, i.e. for each pair
    :math:`a = L_{l,m}, b = L_{l,-m}` (m > 0): :math:`a' = a\cos m\gamma - b\sin m\gamma`,
    :math:`b' = a\sin m\gamma + b\cos m\gamma`."""
    c = np.asarray(coefficients, dtype=np.float64)
    bands = math.isqrt(c.shape[0])
    out = c.copy()
    for l in range(1, bands):
        for m in range(1, l + 1):
            a, b = c[l * (l + 1) + m], c[l * (l + 1) - m]
            cg, sg = math.cos(m * gamma), math.sin(m * gamma)
            out[l * (l + 1) + m] = a * cg - b * sg
            out[l * (l + 1) - m] = a * sg + b * cg
    return out


def sphere_directions(count: int) -> np.ndarray:
    """``count`` nearly uniform unit directions (a Fibonacci lattice), each standing for 4π/count sr."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    phi = math.pi * (3.0 - math.sqrt(5.0)) * k
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def project_directional(direction_from, irradiance, bands: int) -> np.ndarray:
    r"""Coefficients (K, 3) of a directional light arriving from unit ``direction_from`` with
    ``irradiance`` (W/mm², a scalar or per channel): :math:`L_k = E\, Y_k(\omega_l)`."""
    E = np.broadcast_to(np.asarray(irradiance, dtype=np.float64), (3,))
    return basis(np.asarray(direction_from, dtype=np.float64), bands)[:, None] * E[None, :]


def project_environment(radiance, bands: int, directions: int = 20000) -> np.ndarray:
    r"""Coefficients (K, 3) of an environment ``radiance(ω) -> (N, 3)`` (W/(mm² sr)):
    :math:`L_k = \int L\, Y_k\, d\omega`, by the Fibonacci lattice's quadrature."""
    w = sphere_directions(directions)
    return basis(w, bands).T @ np.asarray(radiance(w), dtype=np.float64) * (4.0 * math.pi / directions)
