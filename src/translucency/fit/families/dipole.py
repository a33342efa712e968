"""The family ``dipole``: Jensen et al. 2001's dipole with per-point, per-channel σ_a, σ_s'."""

from ...model import DipoleModel
from ...model.dipole import dipole_R_d
from ._baseline import PhysicalFamily


class DipoleFamily(PhysicalFamily):
    """Jensen's dipole (:func:`translucency.model.dipole_R_d`)."""

    name = "dipole"
    model = DipoleModel
    R_d = staticmethod(dipole_R_d)
    time_terms = {"overhead": 0.3, "point_pixels": 2.5e-6}
