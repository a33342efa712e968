"""Fitting models to measurements.

:func:`fit_exponential_profile` fits a radial sum of exponentials by variable
projection; the per-incident-point fitters of planar data (:func:`fit_planar`)
and of mesh data (:func:`fit_mesh`) build on it, sharing one alternation
(:mod:`._rounds`), one result type (:class:`FitResult`) and one protocol of model
families (:data:`FAMILIES`, :mod:`.families`).
"""

from ..solvers import fit_exponentials_batched
from ._chunk import FIT_BLOCK
from ._options import KINDS, WEIGHTINGS, FitContext, FitResult, check_fit_options
from .families import FAMILIES, Family
from .mesh import fit_mesh
from .planar import PlanarFit, default_chunk_points, fit_planar
from .profile import ProfileFit, fit_burley_profile, fit_dipole_profile, fit_exponential_profile

__all__ = [
    "FAMILIES",
    "FIT_BLOCK",
    "KINDS",
    "WEIGHTINGS",
    "Family",
    "FitContext",
    "FitResult",
    "PlanarFit",
    "ProfileFit",
    "check_fit_options",
    "default_chunk_points",
    "fit_burley_profile",
    "fit_dipole_profile",
    "fit_exponential_profile",
    "fit_exponentials_batched",
    "fit_mesh",
    "fit_planar",
]
