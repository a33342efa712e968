"""Fitting models to measurements.

:func:`fit_exponential_profile` fits a radial sum of exponentials by variable
projection; the per-incident-point fitters of planar and mesh data build on it.
"""

from .profile import ProfileFit, fit_burley_profile, fit_dipole_profile, fit_exponential_profile

__all__ = ["ProfileFit", "fit_burley_profile", "fit_dipole_profile", "fit_exponential_profile"]
