"""Evaluation: error measures, profiles and figures that compare models with data and with each other."""

from .baselines import MaterialProfiles, material_profiles, plot_profiles

__all__ = ["MaterialProfiles", "material_profiles", "plot_profiles"]
