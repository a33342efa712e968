"""Reflectance models: the paper's eq. (1) and the baselines it is compared with.

==========================  =====================================================
:class:`ExponentialModel`   eq. (1): Σ_l w_l (1, s_g, s_b) Σ_k c_kl e^{d_kl r}, α(x_o)
:class:`DipoleModel`        Jensen et al. 2001 dipole per x_i, with α(x_o)
:class:`BurleyModel`        Christensen & Burley 2015 normalized diffusion, with α(x_o)
:class:`PlanarAlpha`        α on a pixel grid over a planar sample
:class:`VertexAlpha`        α per mesh vertex
:func:`direction_weights`   w_l(θ), the anisotropic blend
:data:`MATERIALS`           Jensen 2001 measured coefficients
:func:`check_physics`       per-point bounds: total reflectance ≤ 1, energy radius within the object
==========================  =====================================================
"""

from ._base import ReflectanceModel
from .alpha import PlanarAlpha, VertexAlpha
from .bounds import PhysicsCheck, check_physics, model_extent
from .burley import BurleyModel, burley_energy_within, burley_R, burley_shape
from .dipole import (
    DipoleModel,
    dipole_coefficients,
    dipole_energy_within,
    dipole_R_d,
    dipole_total_reflectance,
    fresnel_diffuse_reflectance,
)
from .directions import direction_angles, direction_weights
from .exponential import ExponentialModel
from .materials import MATERIALS, Material, material

__all__ = [
    "ReflectanceModel",
    "ExponentialModel",
    "DipoleModel",
    "BurleyModel",
    "PlanarAlpha",
    "VertexAlpha",
    "direction_angles",
    "direction_weights",
    "dipole_coefficients",
    "dipole_R_d",
    "dipole_energy_within",
    "dipole_total_reflectance",
    "fresnel_diffuse_reflectance",
    "burley_R",
    "burley_energy_within",
    "burley_shape",
    "MATERIALS",
    "Material",
    "material",
    "check_physics",
    "model_extent",
    "PhysicsCheck",
]
