"""Either kind of data set at a path: :func:`open_any_dataset` opens it once and returns the planar or
the mesh data set it holds (:mod:`translucency.io.dataset`, :mod:`translucency.io.mesh_dataset`), checked.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> import numpy as np
>>> from translucency.io.dataset import write_dataset
>>> path = write_dataset(Path(tempfile.mkdtemp()) / "d.zarr", [[1.0, 1.0]], [[0.0, 0.0]],
...                      np.full((1, 8, 8, 3), 0.01), 0.25).path
>>> type(open_any_dataset(path)).__name__
'PlanarDataset'
"""

from __future__ import annotations

from ._store import open_store
from .dataset import PlanarDataset
from .mesh_dataset import MeshDataset


def open_any_dataset(path, *, writable: bool = False) -> PlanarDataset | MeshDataset:
    """The data set at ``path``, planar or mesh as its header says, opened once and checked; one-line
    errors name the fault (:func:`~translucency.io._store.open_store`).  Read-only unless ``writable``."""
    return open_store(path, (PlanarDataset, MeshDataset), writable=writable)
