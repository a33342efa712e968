"""Reflectance models: the paper's eq. (1) and the baselines it is compared with.

==========================  =====================================================
:class:`ExponentialModel`   eq. (1): Σ_l w_l (1, s_g, s_b) Σ_k c_kl e^{d_kl r}, α(x_o)
:class:`DipoleModel`        Jensen et al. 2001 dipole per x_i, with α(x_o)
:class:`BurleyModel`        Christensen & Burley 2015 normalized diffusion, with α(x_o)
:class:`PBDModel`           Habel et al. 2013 photon beam diffusion per x_i, with α(x_o)
:class:`DirectionalDipoleModel`  Frisvad et al. 2014 directional dipole (normal incidence), with α(x_o)
:class:`PlanarAlpha`        α on a pixel grid over a planar sample
:class:`VertexAlpha`        α per mesh vertex
:func:`direction_weights`   w_l(θ), the anisotropic blend
:data:`MATERIALS`           Jensen 2001 measured coefficients
:data:`MODEL_KINDS`         the model classes by the kind a model file stores
:func:`check_physics`       per-point bounds: total reflectance ≤ 1, energy beyond the object
:class:`Rectangle`          the object a model describes (also ``Diameter``, ``SemiInfinite``)
==========================  =====================================================
"""

from ._base import ReflectanceModel
from .alpha import PlanarAlpha, VertexAlpha
from .bounds import PhysicsCheck, check_physics, model_extent, object_extent
from .burley import BurleyModel, burley_energy_within, burley_R, burley_shape
from .dipole import (
    DipoleModel,
    dipole_coefficients,
    dipole_energy_within,
    dipole_R_d,
    dipole_total_reflectance,
    fresnel_diffuse_reflectance,
)
from .directional_dipole import (
    DirectionalDipoleModel,
    directional_dipole_coefficients,
    directional_dipole_R_d,
)
from .directions import direction_angles, direction_weights
from .exponential import ExponentialModel
from .extent import Diameter, ObjectExtent, Rectangle, SemiInfinite, extent_from_dict
from .materials import MATERIALS, Material, material
from .pbd import PBDModel, fresnel_moment, pbd_coefficients, pbd_R_d, pbd_total_without_kappa

#: the model classes by ``kind``, the name a model file's header stores (:mod:`translucency.io.model_file`);
#: each class declares what it stores (``STORED``, ``header_fields``, ``from_stored``)
MODEL_KINDS: dict[str, type[ReflectanceModel]] = {
    cls.kind: cls for cls in (ExponentialModel, DipoleModel, BurleyModel, PBDModel, DirectionalDipoleModel)
}

__all__ = [
    "MODEL_KINDS",
    "ReflectanceModel",
    "ExponentialModel",
    "DipoleModel",
    "BurleyModel",
    "PBDModel",
    "DirectionalDipoleModel",
    "pbd_R_d",
    "pbd_coefficients",
    "pbd_total_without_kappa",
    "fresnel_moment",
    "directional_dipole_R_d",
    "directional_dipole_coefficients",
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
    "object_extent",
    "PhysicsCheck",
    "ObjectExtent",
    "Rectangle",
    "Diameter",
    "SemiInfinite",
    "extent_from_dict",
]
