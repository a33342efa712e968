"""A data set's incident points, some of them: the same store (planar or mesh) holding only the points
chosen, written beside the work that needs it (a fit's structure is chosen on a subset of the points,
:mod:`translucency.fit.structure`).  The outgoing side (windows, vertices) is copied whole."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .datasets import open_any_dataset

__all__ = ["point_subset"]

#: the per-point arrays every store writes whole (its PER_POINT arrays are written chunk by chunk)
_WHOLE_PER_POINT = ("x_i", "window_origin", "incident", "flags", "R_d_var", "unscattered")


def point_subset(store, points, folder):
    """Write the data set ``store`` restricted to the incident points ``points`` at ``folder``; return it
    opened.

    Parameters
    ----------
    store : PlanarDataset or MeshDataset
        A finished data set.
    points : array_like of int
        Indices of the incident points to keep (in this order).
    folder : path
        A new Zarr directory (a temporary one: the subset is a working copy).

    Returns
    -------
    PlanarDataset or MeshDataset
        Of the same kind as ``store``, with ``len(points)`` points in one chunk.

    Examples
    --------
    >>> import tempfile, numpy as np
    >>> from translucency.io.dataset import write_dataset
    >>> folder = Path(tempfile.mkdtemp())
    >>> R_d = np.arange(4 * 2 * 2 * 3, dtype=np.float32).reshape(4, 2, 2, 3)
    >>> ds = write_dataset(folder / "d.zarr", np.arange(8.0).reshape(4, 2), np.zeros((4, 2)), R_d, 0.25)
    >>> sub = point_subset(ds, [3, 1], folder / "sub.zarr")
    >>> sub.n_points, sub["x_i"].tolist(), bool((sub["R_d"] == R_d[[3, 1]]).all())
    (2, [[6.0, 7.0], [2.0, 3.0]], True)
    """
    import zarr  # heavy: Zarr loads where a store is written

    points = np.asarray(points, dtype=np.int64)
    k = len(points)
    header = {**store.header, "n_points": k, "chunk_points": k}
    root = zarr.create_group(str(Path(folder)), attributes={store.HEADER_KEY: header}, overwrite=False)
    per_point = set(store.PER_POINT) | set(_WHOLE_PER_POINT)
    for name in store.group.array_keys():
        arr = store.group[name]
        if name == "chunk_done":
            data, chunks = np.ones(1, dtype=bool), (1,)
        elif name in per_point:
            data = np.asarray(arr.get_orthogonal_selection((points,)))
            chunks = (k, *arr.shape[1:])
        else:
            data, chunks = np.asarray(arr[...]), arr.chunks
        out = root.create_array(name, shape=data.shape, dtype=arr.dtype, chunks=chunks, fill_value=0,
                                config={"write_empty_chunks": True})  # fmt: skip
        out[...] = data
    return open_any_dataset(folder)
