"""Fitting models to measurements.

:func:`fit_exponential_profile` fits a radial sum of exponentials by variable
projection; the per-incident-point fitters of planar data (:func:`fit_planar`)
and of mesh data (:func:`fit_mesh`) build on it, sharing one alternation
(:mod:`._rounds`), one result type (:class:`FitResult`) and one protocol of model
families (:data:`FAMILIES`, :mod:`.families`), typed against the fit's public types: what every chunk
shares (:class:`FitContext`, :mod:`.options`), the parameters (:class:`FitState`, :class:`Params`,
:mod:`.state`) and a chunk's data (:class:`Chunk`, :mod:`.chunk`).
"""

from ..solvers import fit_exponentials_batched
from .chunk import FIT_BLOCK, Chunk
from .context import FitContext
from .families import FAMILIES, Family, describe_families
from .mesh import fit_mesh
from .options import KINDS, WEIGHTINGS, FitResult, check_fit_options
from .planar import PlanarFit, default_chunk_points, fit_planar
from .profile import ProfileFit, fit_burley_profile, fit_dipole_profile, fit_exponential_profile
from .state import FitState, Params

__all__ = [
    "FAMILIES",
    "FIT_BLOCK",
    "KINDS",
    "WEIGHTINGS",
    "Chunk",
    "Family",
    "FitContext",
    "FitResult",
    "FitState",
    "Params",
    "PlanarFit",
    "ProfileFit",
    "check_fit_options",
    "default_chunk_points",
    "describe_families",
    "fit_burley_profile",
    "fit_dipole_profile",
    "fit_exponential_profile",
    "fit_exponentials_batched",
    "fit_mesh",
    "fit_planar",
]
