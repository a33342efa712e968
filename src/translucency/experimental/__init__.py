"""Experiments kept for a benchmark or an ablation: **unstable** — names, behaviour and results may change
in any release, and nothing here is part of the documented surface.

- :class:`~.scene.ReducedScene`: a fitted scene whose irradiance is traced at a reduced vertex set
  (:mod:`.reduced`), for ``benchmarks/scene_speed.py``;
- :mod:`.incidence`: the incidence law's ablations as transports (``half-space-in``,
  ``normal-incidence``), for ``benchmarks/objects_table.py``.
"""

from . import incidence
from .scene import ReducedScene

__all__ = ["ReducedScene", "incidence"]
