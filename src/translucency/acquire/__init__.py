"""Virtual DISCO: measurements simulated by photon transport on Mitsuba 3 / Dr.Jit.

:func:`acquire_planar` scans a grid of pencil beams over a heterogeneous slab
(:class:`Volume`, made by :func:`make_sample` or :func:`load_volume`) and
writes a chunked, resumable data set (:mod:`translucency.io.dataset`).
"""

from .planar import PlanarSetup, WalkProbe, acquire_planar, estimate_seconds, probe_walk
from .samples import GENERATORS, make_sample
from .volume import Volume, load_volume

__all__ = [
    "PlanarSetup",
    "acquire_planar",
    "estimate_seconds",
    "probe_walk",
    "WalkProbe",
    "GENERATORS",
    "make_sample",
    "Volume",
    "load_volume",
]
