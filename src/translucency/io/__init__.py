"""Files: the versioned model file (:mod:`.model_file`, a per-vertex model's loader in
:mod:`.vertex_model`), the two chunked data sets (:mod:`.dataset` planar, :mod:`.mesh_dataset` per vertex,
one opener for either in :mod:`.datasets`), meshes, atomic writes and what a command may replace
(:mod:`.outputs`)."""

from .model_file import (
    FORMAT,
    VERSION,
    ModelFileError,
    load_model,
    read_header,
    read_model,
    save_model,
)
from .vertex_model import check_vertex_model, load_vertex_model

__all__ = [
    "FORMAT",
    "VERSION",
    "ModelFileError",
    "check_vertex_model",
    "load_model",
    "load_vertex_model",
    "read_header",
    "read_model",
    "save_model",
]
