"""A lab's photographs as functions: HDR photographs of a scanned laser spot into a data set."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable

from .._validate import TranslucencyError
from ..io.dataset import PlanarDataset
from ..rig import ImportSetup, load_calibration
from ..rig import import_images as import_planar
from ._arguments import as_path

__all__ = ["import_images"]


def import_images(
    folder,
    positions,
    calibration,
    out,
    *,
    overwrite: bool = False,
    views=(),
    progress: Callable[[int, int], None] | None = None,
    scheduler: str | None = "threads",
    **setup,
) -> PlanarDataset:
    """A real rig's HDR photographs of a scanned laser spot → a planar data set.

    Wraps :func:`translucency.rig.import_images` (``translucency import images``).

    Parameters
    ----------
    folder : path
        The images (OpenEXR, Radiance HDR or PFM).
    positions : path or list of Shot
        The table of laser positions (``file,x,y`` in mm), or its rows.
    calibration : Calibration or path
        Homography, radiometric scale and corrections, or its JSON file.
    out : str or Path
        The data set folder; an unfinished import of the same inputs resumes.
    overwrite, progress, scheduler
        As in :func:`acquire_planar`.
    views : sequence of (folder, positions, Calibration)
        Further cameras photographing the same laser positions.
    **setup
        Fields of :class:`translucency.rig.ImportSetup`: ``pitch``, ``window``, ``supersample``,
        ``specular_radius``, ``dilate``, ``floor``, ``sample_size``, ``eta``, ``chunk_points``,
        ``dtype``, ``beam_rms``.

    Returns
    -------
    PlanarDataset

    Examples
    --------
    >>> import tempfile, numpy as np, translucency as tl
    >>> from pathlib import Path
    >>> from translucency.rig import Calibration, Homography, write_pfm
    >>> d = Path(tempfile.mkdtemp())
    >>> write_pfm(d / "a.pfm", np.full((64, 64, 3), 2.0, np.float32))
    >>> _ = (d / "pos.csv").write_text("file,x,y\\na.pfm,3.2,3.2\\n")
    >>> cal = Calibration(Homography.from_matrix([[10, 0, 0], [0, 10, 0], [0, 0, 1]]), scale=4.0)
    >>> out = Path(tempfile.mkdtemp()) / "out.zarr"
    >>> ds = tl.import_images(d, d / "pos.csv", cal, out, pitch=0.5, window=2.5)
    >>> ds.window
    (5, 5)
    """
    fields = {f.name for f in dataclasses.fields(ImportSetup)}
    unknown = sorted(set(setup) - fields)
    if unknown:
        raise TranslucencyError(f"{unknown[0]}: not a field of ImportSetup ({', '.join(sorted(fields))})")
    folder, out = as_path("folder", folder), as_path("out", out)
    if isinstance(calibration, (str, os.PathLike)):
        calibration = load_calibration(calibration)
    inputs = [folder] + ([positions] if isinstance(positions, (str, os.PathLike)) else [])
    return import_planar(
        folder,
        positions,
        calibration,
        out,
        ImportSetup(**setup),
        overwrite=overwrite,
        inputs=inputs,
        progress=progress,
        views=views,
        scheduler=scheduler,
    )
