"""The family ``ddipole``: the directional dipole (Frisvad et al. 2014) at normal incidence, σ_a, σ_s'."""

from ...model import DirectionalDipoleModel
from ...model.directional_dipole import directional_dipole_R_d
from ._baseline import PhysicalFamily


class DirectionalDipoleFamily(PhysicalFamily):
    """The directional dipole at normal incidence (:func:`translucency.model.directional_dipole_R_d`)."""

    name = "ddipole"
    summary = "directional dipole at normal incidence"
    model = DirectionalDipoleModel
    R_d = staticmethod(directional_dipole_R_d)
    time_terms = {"overhead": 0.3, "point_pixels": 1.7e-6}
