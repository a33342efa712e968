"""Mitsuba 3 / Dr.Jit: the engine on the right backend, and scenes built from our arrays.

:func:`mitsuba` imports Mitsuba with a working variant (LLVM on the CPU with the
libLLVM of the ``karellen-llvm-core`` wheel, CUDA when present);
:mod:`.scenes` turns meshes, volumes and ray sets into Mitsuba objects, :mod:`.sensors` our cameras
into Mitsuba's.  Every
stage that talks to Mitsuba goes through here.
"""

from ._engine import drjit, engine_versions, mitsuba, prepare_libllvm
from .scenes import (
    NO_ROULETTE,
    SPOT_BEAM_FRACTION,
    checkerboard_scene,
    load_plugin,
    load_with_mesh,
    markers_scene,
    mesh_scene,
    object_volpath_scene,
    object_window_scene,
    rays,
    slab_medium_dict,
    slab_scene,
    spot_dict,
    vertex_radiance_scene,
    write_ply,
)
from .sensors import look_at, perspective_camera_dict, perspective_to_world_dict, pinhole_sensor_dict

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
    "NO_ROULETTE",
    "load_plugin",
    "perspective_camera_dict",
    "perspective_to_world_dict",
    "pinhole_sensor_dict",
    "vertex_radiance_scene",
    "object_volpath_scene",
    "object_window_scene",
    "slab_scene",
    "markers_scene",
    "checkerboard_scene",
]
