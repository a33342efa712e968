"""Virtual DISCO: measurements simulated by photon transport on Mitsuba 3 / Dr.Jit.

:func:`acquire_planar` scans a grid of pencil beams over a heterogeneous slab
(:class:`Volume`, made by :func:`make_sample` or :func:`load_volume`) and
writes a chunked, resumable data set (:mod:`translucency.io.dataset`).

The names below load on first use (the walk, Dask and SciPy are heavy; the CLI's ``--help`` reads
only :data:`GENERATORS`).
"""

from importlib import import_module

from .names import GENERATORS

#: name → the module of this package that defines it
_LAZY = {
    "PlanarSetup": ".planar",
    "acquire_planar": ".planar",
    "estimate_seconds": ".planar",
    "probe_walk": ".planar",
    "WalkProbe": ".planar",
    "make_sample": ".samples",
    "Volume": ".volume",
    "load_volume": ".volume",
}

__all__ = [*_LAZY, "GENERATORS"]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(import_module(_LAZY[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
