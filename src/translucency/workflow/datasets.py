"""Data sets as the library opens them: a planar or a mesh data set, whichever a folder holds."""

from __future__ import annotations

from ..io.dataset import PlanarDataset
from ..io.datasets import open_any_dataset
from ..io.mesh_dataset import MeshDataset
from ._arguments import as_path

__all__ = ["open_dataset"]


def open_dataset(path) -> PlanarDataset | MeshDataset:
    """Open a planar or a mesh data set, whichever ``path`` holds.

    Parameters
    ----------
    path : str or Path
        A data set folder (``.zarr``) written by :func:`acquire_planar`, :func:`acquire_mesh` or
        :func:`import_images`.

    Returns
    -------
    PlanarDataset or MeshDataset
        Arrays are read lazily (``ds["R_d"]``, ``ds.read("R_d", 0, 16)``); ``ds.header`` holds the
        acquisition.

    Raises
    ------
    TranslucencyError
        No such folder, not a data set, or a damaged header.

    Examples
    --------
    >>> import translucency as tl
    >>> ds = tl.open_dataset(tl.data.default_dataset_path())
    >>> ds.n_points, ds.window, ds.pitch
    (1024, (33, 33), 0.25)
    """
    return open_any_dataset(as_path("path", path))
