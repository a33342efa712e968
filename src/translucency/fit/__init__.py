"""Fitting models to measurements.

:func:`fit_exponential_profile` fits a radial sum of exponentials by variable
projection; the per-incident-point fitters of planar data (:func:`fit_planar`)
and of mesh data (:func:`fit_mesh`) build on it, sharing one alternation
(:mod:`._alternation`) and one result type (:class:`FitResult`).
"""

from ._alternation import FitResult, check_fit_options
from ._varpro import fit_exponentials_batched
from .mesh import fit_mesh
from .planar import PlanarFit, fit_planar
from .profile import ProfileFit, fit_burley_profile, fit_dipole_profile, fit_exponential_profile

__all__ = [
    "FitResult",
    "PlanarFit",
    "ProfileFit",
    "check_fit_options",
    "fit_burley_profile",
    "fit_dipole_profile",
    "fit_exponential_profile",
    "fit_exponentials_batched",
    "fit_mesh",
    "fit_planar",
]
