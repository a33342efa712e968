"""Files: the versioned model file (and, later, chunked data sets)."""

from .model_file import (
    FORMAT,
    VERSION,
    ModelFileError,
    load_model,
    load_vertex_model,
    read_header,
    save_model,
)

__all__ = [
    "FORMAT",
    "VERSION",
    "ModelFileError",
    "load_model",
    "load_vertex_model",
    "read_header",
    "save_model",
]
