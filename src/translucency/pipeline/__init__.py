"""The main job and the recipes of its embedded data.

:mod:`.demo` (:func:`run_demo`, what ``make demo`` / ``translucency demo`` runs, and :data:`DEMO_FITS`),
:mod:`.default_data` (the embedded data of Figure 1: :func:`write_default_data`, ``make default-data``),
:mod:`.relight_check` (the relighting check) and :mod:`.figure2` (Figure 2 and its reference:
:func:`write_figure2_reference`, ``make default-reference``).
"""

from .default_data import (
    DEFAULT_ACQUISITIONS,
    DEFAULT_SAMPLE,
    DEFAULT_SCAN,
    FINE_PROFILES,
    default_setup,
    demo_volume,
    fine_profiles,
    profile_points,
    write_default_data,
)
from .demo import DEMO_FITS, run_demo
from .figure2 import FIGURE2_REFERENCE_SPP, figure2_scene, run_figure2, write_figure2_reference
from .relight_check import RELIGHT_RADIUS_WINDOWS, relight_check

__all__ = [
    "DEFAULT_ACQUISITIONS",
    "DEFAULT_SAMPLE",
    "DEFAULT_SCAN",
    "DEMO_FITS",
    "FIGURE2_REFERENCE_SPP",
    "FINE_PROFILES",
    "RELIGHT_RADIUS_WINDOWS",
    "default_setup",
    "demo_volume",
    "figure2_scene",
    "fine_profiles",
    "profile_points",
    "relight_check",
    "run_demo",
    "run_figure2",
    "write_default_data",
    "write_figure2_reference",
]
