"""Virtual DISCO as functions: a planar sample or an object scanned by photon transport into a data set."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from .._validate import TranslucencyError, check_option
from ..acquire import PlanarSetup, Volume, make_sample
from ..acquire import acquire_planar as scan_planar
from ..acquire.mesh import acquire_mesh as scan_mesh
from ..acquire.mesh import object_volume
from ..io.dataset import PlanarDataset
from ..io.mesh import load_mesh
from ..io.mesh_dataset import MeshDataset, open_mesh_dataset
from ._arguments import as_path, one_or_two, volume_of, whole_number

__all__ = ["acquire_mesh", "acquire_planar", "make_sample"]


def acquire_planar(
    sample,
    out,
    *,
    grid=8,
    span=8.0,
    pitch: float = 0.25,
    window: float = 8.0,
    photons: int = 10_000,
    seed: int = 0,
    angle: float = 0.0,
    index_matched: bool = False,
    chunk_points: int = 16,
    dtype: str = "float32",
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
    scheduler: str | None = "threads",
) -> PlanarDataset:
    """Virtual DISCO: scan pencil beams over a planar sample by photon transport; write a data set.

    Wraps :func:`translucency.acquire.acquire_planar` (``translucency acquire planar``).

    Parameters
    ----------
    sample : Volume or path
        The slab (:func:`make_sample`), or a ``.npz`` with ``sigma_s``, ``sigma_a`` (Z, Y, X, 3) in
        mm⁻¹ and ``voxel_mm``.
    out : str or Path
        The data set folder; an unfinished acquisition with the same arguments resumes.
    grid : int or (int, int)
        Incident points per axis.
    span : float or (float, float)
        Side of the incident grid, mm, centred on the sample.
    pitch, window : float
        Pixel size and window side, mm.
    photons, seed : int
        Photons per incident point and channel; their random seed.
    angle : float
        Angle of incidence from the normal, degrees.
    index_matched : bool
        No Fresnel reflection at the boundary.
    chunk_points : int
        Incident points per chunk (the unit of resuming).
    dtype : {"float32", "float16"}
        Storage of R_d and its variance.
    overwrite : bool
        Replace a data set of translucency made with other arguments (never anything else).
    progress : callable(done, total), optional
    scheduler : str, optional
        ``"threads"``, ``"local:N"`` or ``"tcp://HOST:PORT"``; the data are the same bit for bit.

    Returns
    -------
    PlanarDataset

    Raises
    ------
    TranslucencyError
        A bad argument (named), or ``out`` holds something translucency may not replace.

    Examples
    --------
    >>> import tempfile, translucency as tl
    >>> slab = tl.make_sample("homogeneous:marble", (6.0, 6.0, 2.0), 1.0)
    >>> ds = tl.acquire_planar(slab, tempfile.mkdtemp() + "/d.zarr", grid=2, span=2.0, window=2.0,
    ...                        photons=200)  # doctest: +SKIP
    >>> ds.n_points, ds.window  # doctest: +SKIP
    (4, (9, 9))
    """
    out = as_path("out", out)
    volume = volume_of("sample", sample)
    setup = PlanarSetup(
        grid=one_or_two("grid", grid, lambda v: whole_number("grid", v)),
        span=one_or_two("span", span, lambda v: float(check_option("span", v, lo=0))),
        pitch=float(check_option("pitch", pitch, lo=0, open_lo=True)),
        window=float(check_option("window", window, lo=0, open_lo=True)),
        photons=whole_number("photons", photons),
        seed=whole_number("seed", seed, lo=0),
        theta_inc_deg=float(check_option("angle", angle, lo=0, hi=90, open_hi=True)),
        index_matched=bool(index_matched),
        chunk_points=whole_number("chunk_points", chunk_points),
        dtype=dtype,
    )
    inputs = [sample] if isinstance(sample, (str, os.PathLike)) else []
    return scan_planar(
        volume, setup, out, overwrite=overwrite, inputs=inputs, progress=progress, scheduler=scheduler
    )


def acquire_mesh(
    mesh,
    out,
    sample="marble",
    *,
    voxel_mm: float = 0.5,
    g: float = 0.0,
    points: int = 64,
    photons: int = 20_000,
    seed: int = 0,
    chunk_points: int = 8,
    index_matched: bool = False,
    scale_mm: float = 1.0,
    up: str = "z",
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
    scheduler: str | None = "threads",
) -> MeshDataset:
    """Virtual DISCO on an object: pencil beams at surface points of a closed mesh, exits per vertex.

    Wraps :func:`translucency.acquire.mesh.acquire_mesh` (``translucency acquire mesh``).

    Parameters
    ----------
    mesh : trimesh.Trimesh or path
        A closed surface in mm, or a mesh file (OBJ, PLY, STL, …) read with ``scale_mm`` and ``up``.
    out : str or Path
        The mesh data set folder; an unfinished acquisition with the same arguments resumes.
    sample : str, Volume or path
        The filling: a generator name (``"marble"``, ``"homogeneous:skin1"``, …) made over the mesh's
        bounding box at ``voxel_mm`` with ``g`` and ``seed``, a Volume, or a ``.npz`` volume.
    points : int
        Incident points (a farthest-point sample of the vertices).
    photons, seed, chunk_points : int
        Photons per point and channel, random seed, incident points per chunk.
    index_matched : bool
        No Fresnel reflection at the surface.
    scale_mm, up
        Millimetres per file unit and the file's up axis (a mesh file only).
    overwrite, progress, scheduler
        As in :func:`acquire_planar`.

    Returns
    -------
    MeshDataset

    Examples
    --------
    >>> import tempfile, trimesh, translucency as tl
    >>> ball = trimesh.creation.icosphere(2, radius=4.0)
    >>> ds = tl.acquire_mesh(ball, tempfile.mkdtemp() + "/ball.zarr", "homogeneous:marble", voxel_mm=1.0,
    ...                      points=4, photons=300, index_matched=True)  # doctest: +SKIP
    >>> ds.n_points  # doctest: +SKIP
    4
    """
    out = as_path("out", out)
    inputs = []
    if isinstance(mesh, (str, os.PathLike)):
        inputs.append(mesh)
        mesh = load_mesh(mesh, scale_mm=scale_mm, up=up)
    elif not hasattr(mesh, "vertices") or not hasattr(mesh, "faces"):
        raise TranslucencyError(f"mesh: expected a trimesh.Trimesh or a mesh file, got {type(mesh).__name__}")
    if isinstance(sample, str) and Path(sample).suffix != ".npz":
        check_option("voxel_mm", voxel_mm, lo=0, open_lo=True)
        check_option("g", g, lo=-1, hi=1, open_lo=True, open_hi=True)
        volume = object_volume(
            sample, mesh, float(voxel_mm), g=float(g), seed=whole_number("seed", seed, lo=0)
        )
    else:
        volume = volume_of("sample", sample)
        if not isinstance(sample, Volume):
            inputs.append(sample)
    scan_mesh(
        mesh,
        volume,
        out,
        n_points=whole_number("points", points),
        photons=whole_number("photons", photons),
        seed=whole_number("seed", seed, lo=0),
        chunk_points=whole_number("chunk_points", chunk_points),
        index_matched=bool(index_matched),
        overwrite=overwrite,
        inputs=inputs,
        progress=progress,
        scheduler=scheduler,
    )
    return open_mesh_dataset(out)
