"""Mitsuba 3 / Dr.Jit: the engine on the right backend, and scenes built from our arrays.

:func:`mitsuba` imports Mitsuba with a working variant (LLVM on the CPU with the
libLLVM of the ``karellen-llvm-core`` wheel, CUDA when present);
:mod:`.scenes` turns meshes, volumes and ray sets into Mitsuba objects.  Every
stage that talks to Mitsuba goes through here.
"""

from ._engine import drjit, engine_versions, mitsuba, prepare_libllvm
from .scenes import (
    SPOT_BEAM_FRACTION,
    load_with_mesh,
    look_at,
    mesh_scene,
    rays,
    slab_medium_dict,
    spot_dict,
    write_ply,
)

__all__ = [
    "mitsuba",
    "drjit",
    "engine_versions",
    "prepare_libllvm",
    "rays",
    "write_ply",
    "load_with_mesh",
    "mesh_scene",
    "slab_medium_dict",
    "look_at",
    "spot_dict",
    "SPOT_BEAM_FRACTION",
]
