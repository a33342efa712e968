"""The family ``pbd``: photon beam diffusion (Habel et al. 2013) with per-point, per-channel σ_a, σ_s'."""

from ...model import PBDModel
from ...model.pbd import pbd_R_d
from ._baseline import PhysicalFamily


class PBDFamily(PhysicalFamily):
    """Photon beam diffusion (:func:`translucency.model.pbd_R_d`)."""

    name = "pbd"
    summary = "photon beam diffusion"
    model = PBDModel
    R_d = staticmethod(pbd_R_d)
    time_terms = {"overhead": 0.3, "point_pixels": 7.4e-5}

    def medium(self, ctx) -> dict:
        """The single scattering's phase function: the data set's g (its medium's mean cosine)."""
        return {"g": ctx.g}
