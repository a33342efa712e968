"""Evaluation: error measures, profiles and figures that compare models with data and with each other.

:mod:`.errors` (rel_l2 per band, error maps), :mod:`.rings` (ring means), :mod:`.directions` (an
anisotropic model's spreading direction), the report's figures (:mod:`.profile_figure`, :mod:`.error_maps`,
:mod:`.model_maps`), its summary (:mod:`.summary`; its sentences: :mod:`.conclusion`) and page
(:mod:`.page`), put together by :mod:`.report`; :mod:`.baselines` (dipole, Burley and exponential fits
per material) and :mod:`.relight`.
"""

from .baselines import MaterialProfiles, material_profiles, plot_profiles

__all__ = ["MaterialProfiles", "material_profiles", "plot_profiles"]
