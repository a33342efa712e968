"""Measured scattering coefficients of Jensen et al. 2001.

Source: H. W. Jensen, S. R. Marschner, M. Levoy, P. Hanrahan, "A Practical
Model for Subsurface Light Transport", SIGGRAPH 2001, Figure 5 (table of
measured :math:`\\sigma_s'` and :math:`\\sigma_a` in mm⁻¹ for the R, G, B
channels, with the resulting total diffuse reflectance :math:`R_d`).  All
materials were measured with :math:`\\eta = 1.3`.  The same numbers are used
by pbrt (``SubsurfaceParameterTable``) and many other renderers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError

#: relative index of refraction used for every material of the table
ETA = 1.3


@dataclass(frozen=True)
class Material:
    """One row of the table; coefficients in mm⁻¹, RGB.

    Examples
    --------
    >>> m = MATERIALS["marble"]
    >>> m.eta, m.R_d_published
    (1.3, array([0.83, 0.79, 0.75]))
    >>> m.mean_free_path.round(3)   # 1 / (σ_a + σ_s'), mm
    array([0.456, 0.381, 0.333])
    """

    name: str
    sigma_s_prime: np.ndarray
    sigma_a: np.ndarray
    R_d_published: np.ndarray  # Jensen's total diffuse reflectance column, 2 digits
    eta: float = ETA

    @property
    def mean_free_path(self) -> np.ndarray:
        """Transport mean free path :math:`1/\\sigma_t'` in mm."""
        return 1.0 / (self.sigma_a + self.sigma_s_prime)


# name: (sigma_s' RGB, sigma_a RGB, published R_d RGB)
_TABLE = {
    "apple": ((2.29, 2.39, 1.97), (0.0030, 0.0034, 0.046), (0.85, 0.84, 0.53)),
    "chicken1": ((0.15, 0.21, 0.38), (0.015, 0.077, 0.19), (0.31, 0.15, 0.10)),
    "chicken2": ((0.19, 0.25, 0.32), (0.018, 0.088, 0.20), (0.32, 0.16, 0.10)),
    "cream": ((7.38, 5.47, 3.15), (0.0002, 0.0028, 0.0163), (0.98, 0.90, 0.73)),
    "ketchup": ((0.18, 0.07, 0.03), (0.061, 0.97, 1.45), (0.16, 0.01, 0.00)),
    "marble": ((2.19, 2.62, 3.00), (0.0021, 0.0041, 0.0071), (0.83, 0.79, 0.75)),
    "potato": ((0.68, 0.70, 0.55), (0.0024, 0.0090, 0.12), (0.77, 0.62, 0.21)),
    "skimmilk": ((0.70, 1.22, 1.90), (0.0014, 0.0025, 0.0142), (0.81, 0.81, 0.69)),
    "skin1": ((0.74, 0.88, 1.01), (0.032, 0.17, 0.48), (0.44, 0.22, 0.13)),
    "skin2": ((1.09, 1.59, 1.79), (0.013, 0.070, 0.145), (0.63, 0.44, 0.34)),
    "spectralon": ((11.6, 20.4, 14.9), (0.00, 0.00, 0.00), (1.00, 1.00, 1.00)),
    "wholemilk": ((2.55, 3.21, 3.77), (0.0011, 0.0024, 0.014), (0.91, 0.88, 0.76)),
}

MATERIALS: dict[str, Material] = {
    name: Material(name, np.array(sp), np.array(sa), np.array(rd)) for name, (sp, sa, rd) in _TABLE.items()
}


def material(name: str) -> Material:
    """Look up a material of the Jensen 2001 table by (case-insensitive) name.

    Examples
    --------
    >>> from translucency.model import material
    >>> material("Marble").sigma_s_prime
    array([2.19, 2.62, 3.  ])
    """
    key = name.lower()
    if key not in MATERIALS:
        raise TranslucencyError(f"material: unknown name {name!r}; choose one of {', '.join(MATERIALS)}")
    return MATERIALS[key]
