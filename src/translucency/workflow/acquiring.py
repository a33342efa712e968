"""Virtual DISCO as functions: a planar sample or an object scanned by photon transport into a data set
(:func:`acquire_planar`, :func:`acquire_mesh`), and a virtual rig's photographs of either, written as a
lab hands them over (:func:`acquire_photographs`, :func:`acquire_object_photographs`).

``translucency acquire planar|mesh|photographs|object-photographs`` are these functions: the arguments
checked at the boundary, the memory and time estimated before the work (refused in one line beyond
``max_memory``), the output claimed (an unfinished acquisition with the same arguments resumes; Ctrl-C
keeps the chunks done), the work, and the summary the command prints.  Units: mm, σ in mm⁻¹.
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .. import resources
from .._validate import TranslucencyError, check_option
from ..acquire import PlanarSetup, Volume, estimate_seconds, load_volume, make_sample, probe_walk
from ..acquire import acquire_planar as scan_planar
from ..acquire.mesh import acquire_mesh as scan_mesh
from ..acquire.mesh import check_filling, object_volume
from ..acquire.objects import make_pig
from ..cluster import parse_scheduler
from ..io.dataset import PlanarDataset, open_dataset
from ..io.inputs import expect_input
from ..io.mesh import check_mesh_file, load_mesh
from ..io.mesh_dataset import MeshDataset, open_mesh_dataset
from ..io.outputs import claim_output
from ..resources.run import Reporter, Run, bytes_at, kept_chunks
from ..rig.object.photographs import LaserBeam, photograph_object
from ..rig.planar.photographs import VirtualCamera, photograph_sample
from ._arguments import as_path, one_or_two, volume_of, whole_number

__all__ = [
    "Photographs",
    "acquire_mesh",
    "acquire_object_photographs",
    "acquire_photographs",
    "acquire_planar",
    "make_sample",
]

#: the up axes a mesh file may have (turned to +z)
UP_AXES = ("z", "y", "x")
#: the image formats of a virtual rig's photographs
IMAGE_FORMATS = ("pfm", "exr")


@dataclass
class Photographs:
    """What :func:`acquire_photographs` or :func:`acquire_object_photographs` wrote: the folder a lab would
    hand over, the rig's record of it and the run's summary."""

    folder: Path
    record: dict  # a sample's: homography (true), marked, rms_px, power; an object's: incident, cameras
    summary: dict  # the numbers ``translucency acquire photographs|object-photographs --json`` prints


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
    sample_seed: int | None = None,
    size=(20.0, 20.0, 8.0),
    voxel_mm: float = 0.25,
    g: float = 0.0,
    angle: float = 0.0,
    index_matched: bool = False,
    chunk_points: int = 16,
    dtype: str = "float32",
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
    scheduler: str | None = "threads",
    max_memory: str | int | None = None,
    reporter: Reporter | None = None,
) -> PlanarDataset:
    """Virtual DISCO: scan pencil beams over a planar sample by photon transport; write a data set.

    ``translucency acquire planar`` is this function (:func:`translucency.acquire.acquire_planar` under
    the run's checks, estimates and resuming).

    Parameters
    ----------
    sample : str, Volume or path
        A generator name (``"marble"``, ``"homogeneous:skin1"``, … :data:`translucency.acquire.GENERATORS`)
        made at ``size`` and ``voxel_mm`` with ``g`` and ``sample_seed``; the slab (:func:`make_sample`);
        or a ``.npz`` with ``sigma_s``, ``sigma_a`` (Z, Y, X, 3) in mm⁻¹ and ``voxel_mm``.
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
    sample_seed : int, optional
        Seed of a generated sample (default ``seed``): the same ``sample_seed`` with another ``seed`` is
        a held-out truth of the same sample.
    size : (float, float, float)
        A generated slab's width, height and thickness, mm.
    voxel_mm, g : float
        A generated sample's voxel size (mm) and Henyey-Greenstein anisotropy.
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
    max_memory : str or int, optional
        Most memory the acquisition may use (``"4G"``); a larger estimate is refused before any work.
    reporter : Reporter, optional
        Hears the run's information lines and progress (default: silent).

    Returns
    -------
    PlanarDataset
        With ``.summary``: the numbers of ``translucency acquire planar --json``.

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
    >>> ds.n_points, ds.window, ds.summary["complete"]  # doctest: +SKIP
    (4, (9, 9), True)
    """
    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    out = as_path("out", out)
    setup = _planar_setup(grid, span, pitch, window, photons, seed, angle, index_matched, chunk_points, dtype)
    sample_seed = whole_number("sample_seed", seed if sample_seed is None else sample_seed, lo=0)
    size, voxel_mm, g = _slab(size, voxel_mm, g)
    run = Run("acquire planar", max_memory=max_memory, reporter=reporter)
    name, volume, path = _sample(sample)

    def need(voxels):
        n = resources.memory.planar_acquisition(
            grid=setup.grid,
            pitch=setup.pitch,
            window=setup.window,
            photons=setup.photons,
            chunk=setup.chunk_points,
            voxels=voxels,
            dtype=setup.dtype,
        )
        return run.check(n, out, resumed=True)  # a resumed acquisition keeps what is there

    if name is not None:  # before the sample is generated
        estimate = need(resources.memory.slab_voxels(size, voxel_mm))
    claim_output(out, "planar data set", overwrite=overwrite, inputs=[path], reuse=True)
    if name is not None:
        volume = make_sample(name, size, voxel_mm, g=g, seed=sample_seed)
    else:
        volume = volume if path is None else load_volume(path)
        estimate = need(volume.sigma_s.size / 3)
    setup.check(volume)
    state = _timed_planar(run, volume, setup, out, estimate)
    P = setup.grid[0] * setup.grid[1]
    with run.work("acquire", total=P, fresh=state is None and bytes_at(out) == 0) as work:
        work.update(completed=P - _left(state, P), item="points")
        scan_planar(
            volume,
            setup,
            out,
            overwrite=overwrite,
            inputs=[path],
            progress=_steps(work, progress),
            scheduler=scheduler,
        )
    ds = open_dataset(out)
    ds.summary = run.summary(
        {
            "command": "acquire planar",
            "out": out,
            "points": ds.n_points,
            "window_pixels": ds.window,
            "photons": setup.photons,
            "seed": setup.seed,
            "complete": ds.complete(),
            "seconds": run.seconds(),
        }
    )
    return ds


def _planar_setup(grid, span, pitch, window, photons, seed, angle, index_matched, chunk_points, dtype):
    """The scan's arguments checked, as a :class:`PlanarSetup` (the sample is checked against it later)."""
    pitch = float(check_option("pitch", pitch, lo=0, open_lo=True))
    window = float(check_option("window", window, lo=0, open_lo=True))
    check_option("pitch", pitch, hi=window)  # at least one pixel a window
    if dtype not in ("float32", "float16"):
        raise TranslucencyError(f"dtype: expected float32 or float16, got {dtype!r}")
    return PlanarSetup(
        grid=one_or_two("grid", grid, lambda v: int(check_option("grid", whole_number("grid", v), hi=4096))),
        span=one_or_two("span", span, lambda v: float(check_option("span", v, lo=0))),
        pitch=pitch,
        window=window,
        photons=whole_number("photons", photons),
        seed=whole_number("seed", seed, lo=0),
        theta_inc_deg=float(check_option("angle", angle, lo=0, hi=90, open_hi=True)),
        index_matched=bool(index_matched),
        chunk_points=whole_number("chunk_points", chunk_points),
        dtype=dtype,
    )


def _slab(size, voxel_mm, g) -> tuple[tuple[float, ...], float, float]:
    """A generated slab's size (mm), voxel (mm) and anisotropy, checked."""
    size = tuple(float(check_option("size", v, lo=0, open_lo=True, hi=1e5)) for v in np.atleast_1d(size))
    if len(size) != 3:
        raise TranslucencyError(f"size: expected (width, height, thickness) in mm, got {size!r}")
    voxel_mm = float(check_option("voxel_mm", voxel_mm, lo=0, open_lo=True))
    check_option("voxel_mm", voxel_mm, hi=min(size))  # at least one voxel across the thinnest side
    return size, voxel_mm, float(check_option("g", g, lo=-1, hi=1, open_lo=True, open_hi=True))


def _sample(sample) -> tuple[str | None, Volume | None, Path | None]:
    """(generator name, Volume, .npz path) of ``sample``: exactly one of them is not None."""
    if isinstance(sample, str) and Path(sample).suffix != ".npz":
        return sample, None, None
    if isinstance(sample, (str, os.PathLike)):
        path = Path(sample)
        expect_input(path, ("volume file",), "sample")  # a mesh, a data set, a model: named as such
        return None, None, path
    return None, volume_of("sample", sample), None


def _timed_planar(run: Run, volume: Volume, setup: PlanarSetup, out: Path, estimate) -> Resumed | None:
    """The planar scan's time estimate (from a probe of the walk on ``volume``), its information line and
    its note for Ctrl-C; the data set it resumes, if any."""
    walk = probe_walk(volume, setup)  # a short trace of this volume: its steps a photon, this machine's speed
    P = setup.grid[0] * setup.grid[1]
    state = _resumable(out, open_dataset, lambda request: request.get("setup") == _jsonable(setup))
    share = 1.0 if state is None else state.points_left / P  # what is left of the work
    units = resources.timing.planar_acquisition_units(
        points=round(share * P),
        photon_steps=share * estimate_seconds(volume, setup, steps_per_second=1.0, probe=walk),
        pixels=round(share * P) * setup.window_pixels() ** 2,
    )
    first = resources.timing.probe_factor("acquire planar", "photon_steps", walk.seconds_per_step)
    timing = run.time(units, (first, "from a probe of the walk on this sample"))
    run.kept = lambda: kept_chunks(out, open_dataset)
    run.info(
        f"{_resuming(state)}{round(share * P)} incident points x {setup.photons:,} photons x 3 channels on a "
        f"{' x '.join(f'{v:g}' for v in volume.size_mm)} mm slab; time {timing.text()}, "
        f"memory ~{estimate.memory / 2**20:,.0f} MiB",
    )
    return state


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
    max_memory: str | int | None = None,
    reporter: Reporter | None = None,
) -> MeshDataset:
    """Virtual DISCO on an object: pencil beams at surface points of a closed mesh, exits per vertex.

    ``translucency acquire mesh`` is this function (:func:`translucency.acquire.mesh.acquire_mesh` under
    the run's checks, estimates and resuming).

    Parameters
    ----------
    mesh : trimesh.Trimesh, path or None
        A closed surface in mm, a mesh file (OBJ, PLY, STL, …) read with ``scale_mm`` and ``up``, or
        None: the procedural pig.
    out : str or Path
        The mesh data set folder; an unfinished acquisition with the same arguments resumes.
    sample : str, Volume or path
        The filling: a generator name (``"marble"``, ``"homogeneous:skin1"``, …) made over the mesh's
        bounding box at ``voxel_mm`` with ``g`` and ``seed``, a Volume, or a ``.npz`` volume over that box.
    points : int
        Incident points (a farthest-point sample of the vertices).
    photons, seed, chunk_points : int
        Photons per point and channel, random seed, incident points per chunk.
    index_matched : bool
        No Fresnel reflection at the surface.
    scale_mm, up
        Millimetres per file unit and the file's up axis (a mesh file only).
    overwrite, progress, scheduler, max_memory, reporter
        As in :func:`acquire_planar`.

    Returns
    -------
    MeshDataset
        With ``.summary``: the numbers of ``translucency acquire mesh --json``.

    Examples
    --------
    >>> import tempfile, trimesh, translucency as tl
    >>> ball = trimesh.creation.icosphere(2, radius=4.0)
    >>> ds = tl.acquire_mesh(ball, tempfile.mkdtemp() + "/ball.zarr", "homogeneous:marble", voxel_mm=1.0,
    ...                      points=4, photons=300, index_matched=True)  # doctest: +SKIP
    >>> ds.n_points, ds.summary["vertices"]  # doctest: +SKIP
    (4, 162)
    """
    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    out = as_path("out", out)
    photons, seed = whole_number("photons", photons), whole_number("seed", seed, lo=0)
    points, chunk_points = whole_number("points", points), whole_number("chunk_points", chunk_points)
    g = float(check_option("g", g, lo=-1, hi=1, open_lo=True, open_hi=True))
    scale_mm = float(check_option("scale_mm", scale_mm, lo=0, open_lo=True))
    voxel_mm = float(check_option("voxel_mm", voxel_mm, lo=0, open_lo=True))
    if up not in UP_AXES:  # an option: before the mesh is read
        raise TranslucencyError(f"up: expected one of z, y, x, got {up!r}")
    run = Run("acquire mesh", max_memory=max_memory, reporter=reporter)
    name, volume, path = _sample(sample)
    mesh_file = _mesh_file(mesh)
    claim_output(out, "mesh data set", overwrite=overwrite, inputs=[mesh_file, path], reuse=True)
    obj = _object(mesh, mesh_file, scale_mm, up)
    V = len(obj.vertices)
    if points > V:  # before any estimate: the incident points are vertices of the mesh
        raise TranslucencyError(
            f"points: need 1 to {V:,} incident points (the mesh's vertices), got {points:,}"
        )

    def need(voxels):
        n = resources.memory.mesh_acquisition(
            vertices=V,
            faces=len(obj.faces),
            points=points,
            photons=photons,
            chunk=chunk_points,
            voxels=voxels,
        )
        return run.check(n, out, resumed=True)  # a resumed acquisition keeps what is there

    if name is None:
        volume = volume if path is None else load_volume(path)
        estimate = need(volume.sigma_s.size / 3)
    else:  # before the filling is generated
        estimate = need(resources.memory.object_voxels(obj.extents, voxel_mm))
        volume = object_volume(name, obj, voxel_mm, g=g, seed=seed)
    check_filling(obj, volume)
    same = {"n_points": points, "photons": photons, "seed": seed, "chunk": chunk_points, "vertices": V}
    state = _resumable(out, open_mesh_dataset, lambda request: _matches(request, same))
    timing = run.time(
        resources.timing.mesh_acquisition_units(points=_left(state, points), photons=photons, vertices=V)
    )
    run.kept = lambda: kept_chunks(out, open_mesh_dataset)
    run.info(
        f"{_resuming(state)}{_left(state, points)} incident points x {photons:,} photons x 3 channels on a "
        f"mesh of {V:,} vertices, {' x '.join(f'{v:.1f}' for v in obj.extents)} mm; "
        f"time {timing.text()}, memory ~{estimate.memory / 2**20:,.0f} MiB",
    )
    with run.work("acquire", total=points, fresh=state is None and bytes_at(out) == 0) as work:
        work.update(completed=points - _left(state, points), item="points")
        scan_mesh(
            obj,
            volume,
            out,
            n_points=points,
            photons=photons,
            seed=seed,
            chunk_points=chunk_points,
            index_matched=bool(index_matched),
            overwrite=overwrite,
            inputs=[mesh_file, path],
            progress=_steps(work, progress),
            scheduler=scheduler,
        )
    ds = open_mesh_dataset(out)
    ds.summary = run.summary(
        {
            "command": "acquire mesh",
            "out": out,
            "points": ds.n_points,
            "vertices": V,
            "photons": photons,
            "seed": seed,
            "complete": ds.complete(),
            "seconds": run.seconds(),
        }
    )
    return ds


def _mesh_file(mesh) -> Path | None:
    """The mesh file of ``mesh``, checked (a folder, a missing file or a data set named before the output is
    judged); None for a Trimesh or None (the procedural pig)."""
    if isinstance(mesh, (str, os.PathLike)):
        path = Path(mesh)
        expect_input(path, ("mesh file",), "mesh")
        return check_mesh_file(path, "mesh")
    if mesh is not None and not (hasattr(mesh, "vertices") and hasattr(mesh, "faces")):
        raise TranslucencyError(f"mesh: expected a trimesh.Trimesh or a mesh file, got {type(mesh).__name__}")
    return None


def _object(mesh, path: Path | None, scale_mm: float, up: str):
    """The object: the mesh file at ``path`` read with ``scale_mm`` and ``up``, the Trimesh ``mesh``, or the
    procedural pig for None."""
    if path is not None:
        return load_mesh(path, scale_mm=scale_mm, up=up)
    return make_pig() if mesh is None else mesh


def _steps(work, progress: Callable[[int, int], None] | None) -> Callable[[int, int], None]:
    """The stage's ``progress(done, total)``: the run's progress bar, and the caller's ``progress``."""

    def step(done: int, total: int) -> None:
        work.update(completed=done, item="points")
        if progress is not None:
            progress(done, total)

    return step


def acquire_photographs(
    sample,
    out,
    *,
    grid: int = 2,
    span: float = 4.0,
    size=(12.0, 12.0, 4.0),
    voxel_mm: float = 0.5,
    camera=(0.0, -8.0, 11.0),
    fov: float = 40.0,
    resolution=(64, 64),
    spp: int = 64,
    seed: int = 0,
    image_format: str = "pfm",
    overwrite: bool = False,
    reporter: Reporter | None = None,
) -> Photographs:
    """Photograph a virtual planar sample with Mitsuba 3, as a lab's rig would for
    :func:`translucency.import_images`.

    A narrow beam per incident point, an oblique perspective camera, sensor noise, a dark offset,
    vignetting and saturation; the folder holds ``shot_NNN.pfm|exr``, ``positions.csv``,
    ``calibration.json`` (marked points found in ``markers.pfm``), ``dark.pfm`` and ``flat.pfm``.
    ``translucency acquire photographs`` is this function.

    Parameters
    ----------
    sample : str, Volume or path
        A generator name made at ``size`` and ``voxel_mm`` with ``seed``, a Volume or a ``.npz`` volume.
    out : str or Path
        The folder to write.
    grid : int
        Incident points per axis (1–64).
    span : float
        Side of the incident grid, mm, centred on the sample.
    size : (float, float, float)
        A generated slab's width, height and thickness, mm.
    voxel_mm : float
        A generated sample's voxel size, mm.
    camera : (float, float, float)
        The camera's position relative to the sample's centre, mm (it looks at the centre).
    fov : float
        Horizontal field of view, degrees (1–120).
    resolution : (int, int)
        Image width and height, pixels (8–8192).
    spp, seed : int
        Samples per pixel of Mitsuba's volpath; the random seed of the sample, the renders and the sensor.
    image_format : {"pfm", "exr"}
    overwrite : bool
        Replace an earlier output folder of translucency (never anything else).
    reporter : Reporter, optional
        Hears the run's information line (default: silent).

    Returns
    -------
    Photographs
        ``.folder``, ``.record`` (the true homography, the marked points' ``rms_px``, …), ``.summary``.

    Examples
    --------
    >>> import tempfile, translucency as tl
    >>> shots = tl.acquire_photographs("homogeneous:skin1", tempfile.mkdtemp() + "/shots", grid=1,
    ...                                size=(8, 8, 3), voxel_mm=1.0, spp=8)  # doctest: +SKIP
    >>> ds = tl.import_images(shots.folder, shots.folder / "positions.csv",
    ...                       shots.folder / "calibration.json", "d.zarr", scale=1e5)  # doctest: +SKIP
    """
    grid = int(check_option("grid", whole_number("grid", grid), hi=64))
    spp, seed = whole_number("spp", spp), whole_number("seed", seed, lo=0)
    fov = float(check_option("fov", fov, lo=1, hi=120))
    resolution = _resolution(resolution)
    image_format = _image_format(image_format)
    size, voxel_mm, _ = _slab(size, voxel_mm, 0.0)
    out = as_path("out", out)
    run = Run("acquire photographs", reporter=reporter)
    name, volume, path = _sample(sample)
    run.claim_folder(out, overwrite=overwrite, inputs=[path])
    if name is not None:
        volume = make_sample(name, size, voxel_mm, seed=seed)
    elif path is not None:
        volume = load_volume(path)
    W, H, _ = volume.size_mm
    setup = PlanarSetup(grid=(grid, grid), span=(span, span), pitch=0.25, window=min(W, H) / 2)
    setup.check(volume)
    x_i = setup.incident_points(volume)
    centre = np.array([W / 2, H / 2, 0.0])
    cam = VirtualCamera(tuple(centre + np.asarray(camera)), tuple(centre), fov, *resolution)
    run.info(f"{len(x_i)} photographs x 3 channels at {spp} spp ({resolution[0]} x {resolution[1]} px)")
    record = photograph_sample(volume, x_i, out, camera=cam, spp=spp, seed=seed, image_format=image_format)
    summary = {
        "command": "acquire photographs",
        "out": out,
        "photographs": len(x_i),
        "rms_px": record["rms_px"],
        "homography": np.round(record["homography"].matrix, 4).tolist(),  # the true one, from the pose
        "seconds": run.seconds(),
    }
    return Photographs(out, record, run.summary(summary))


def _resolution(resolution) -> tuple[int, int]:
    """Image width and height, pixels (8–8192)."""
    values = tuple(
        int(check_option("resolution", whole_number("resolution", v), lo=8, hi=8192))
        for v in np.atleast_1d(resolution)
    )
    if len(values) != 2:
        raise TranslucencyError(f"resolution: expected (width, height), got {resolution!r}")
    return values


def _image_format(image_format: str) -> str:
    if image_format not in IMAGE_FORMATS:
        raise TranslucencyError(f"image_format: pfm or exr, got {image_format!r}")
    return image_format


def acquire_object_photographs(
    mesh,
    out,
    *,
    sample: str = "marble",
    scale_mm: float = 1.0,
    up: str = "z",
    voxel_mm: float = 0.5,
    points: int = 8,
    cameras: int = 6,
    resolution=(128, 128),
    spp: int = 64,
    beam_mm: float = 0.3,
    checkerboards: bool = False,
    seed: int = 0,
    image_format: str = "pfm",
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
    reporter: Reporter | None = None,
) -> Photographs:
    """Photograph a virtual object with Mitsuba 3, as a lab's object rig would for
    :func:`translucency.import_object`.

    A laser spot per point, calibrated cameras on a sphere around the object, sensor noise, a dark offset,
    vignetting, a saturated spot and drifting power; the folder holds ``object.json`` (the rig file),
    ``object.ply``, the cameras and the shots.  ``translucency acquire object-photographs`` is this
    function.

    Parameters
    ----------
    mesh : trimesh.Trimesh, path or None
        A closed surface in mm, a mesh file read with ``scale_mm`` and ``up``, or None: the pig.
    out : str or Path
        The folder to write.
    sample : str
        The filling's generator name, made over the mesh's bounding box at ``voxel_mm`` with ``seed``.
    points, cameras : int
        Laser positions (a farthest-point sample of the vertices) and cameras (1–64).
    resolution : (int, int)
        Image width and height, pixels (8–8192).
    spp : int
        Samples per pixel of each of the two repeated frames.
    beam_mm : float
        Radius of the laser's spot on the surface, mm.
    checkerboards : bool
        Give the intrinsics as checkerboard photographs (OpenCV calibrates them on import).
    seed : int
        Random seed of the filling, the renders and the sensor.
    image_format : {"pfm", "exr"}
    overwrite, progress, reporter
        As in :func:`acquire_photographs` (``progress(done, total)``: shots photographed).

    Returns
    -------
    Photographs
        ``.folder``, ``.record`` (``incident`` vertices, true ``cameras``, ``seconds``), ``.summary``.

    Examples
    --------
    >>> import tempfile, translucency as tl
    >>> shots = tl.acquire_object_photographs(None, tempfile.mkdtemp() + "/rig", points=2, cameras=3,
    ...                                       resolution=(64, 64), spp=8)  # doctest: +SKIP
    >>> ds = tl.import_object(shots.folder / "object.json", "pig.zarr")  # doctest: +SKIP
    """
    points = whole_number("points", points)
    cameras = int(check_option("cameras", whole_number("cameras", cameras), hi=64))
    spp, seed = whole_number("spp", spp), whole_number("seed", seed, lo=0)
    beam_mm = float(check_option("beam_mm", beam_mm, lo=0, open_lo=True))
    voxel_mm = float(check_option("voxel_mm", voxel_mm, lo=0, open_lo=True))
    scale_mm = float(check_option("scale_mm", scale_mm, lo=0, open_lo=True))
    resolution, image_format = _resolution(resolution), _image_format(image_format)
    if up not in UP_AXES:
        raise TranslucencyError(f"up: expected one of z, y, x, got {up!r}")
    out, mesh_file = as_path("out", out), _mesh_file(mesh)
    run = Run("acquire object-photographs", reporter=reporter)
    run.claim_folder(out, overwrite=overwrite, inputs=[mesh_file])
    obj = _object(mesh, mesh_file, scale_mm, up)
    if points > len(obj.vertices):
        raise TranslucencyError(f"points: need 1 to {len(obj.vertices):,} laser positions, got {points:,}")
    volume = object_volume(sample, obj, voxel_mm, seed=seed)
    check_filling(obj, volume)
    run.info(
        f"{points} laser positions x {cameras} cameras x 3 channels x 2 frames at {spp} spp "
        f"({resolution[0]} x {resolution[1]} px), mesh of {len(obj.vertices):,} vertices"
    )
    with run.reporter.progress("photograph", points) as update:
        update(item="shots")

        def step(done: int, total: int) -> None:
            update(completed=done)
            if progress is not None:
                progress(done, total)

        record = photograph_object(
            obj,
            volume,
            out,
            n_points=points,
            n_cameras=cameras,
            resolution=resolution,
            spp=spp,
            seed=seed,
            beam=LaserBeam(radius_mm=beam_mm),
            image_format=image_format,
            checkerboards=bool(checkerboards),
            spot_radius_mm=max(0.5, 2 * beam_mm),
            progress=step,
        )
    summary = {
        "command": "acquire object-photographs",
        "out": out,
        "points": points,
        "cameras": cameras,
        "incident": record["incident"],
        "seconds": record["seconds"],
    }
    return Photographs(out, record, run.summary(summary))


# -- resuming -------------------------------------------------------------------------------------------
class Resumed(NamedTuple):
    """A data set an acquisition resumes: its chunks done, of how many, and the points left to acquire."""

    done: int
    chunks: int
    points_left: int


def _chunks_of(ds) -> tuple[np.ndarray, np.ndarray]:
    """The done flags of a data set's chunks and the points of each."""
    done = np.asarray(ds.group["chunk_done"][...], dtype=bool)
    k, P = ds.chunk_points, ds.n_points
    return done, np.array([min(P, (c + 1) * k) - c * k for c in range(len(done))])


def _resumable(out: Path, opener, same) -> Resumed | None:
    """The data set at ``out`` that this acquisition resumes (made with the same arguments: ``same`` of its
    header's request), or None when it starts afresh."""
    try:
        ds = opener(out)
        if not same(ds.header.get("request", {})):
            return None
        done, points = _chunks_of(ds)
    except Exception:  # noqa: BLE001 — no data set, or one that cannot be read: a fresh start (checked later)
        return None
    if not done.any():
        return None
    return Resumed(int(done.sum()), len(done), int(points[~done].sum()))


def _left(state: Resumed | None, points: int) -> int:
    """Incident points left to acquire."""
    return points if state is None else state.points_left


def _matches(request: dict, same: dict) -> bool:
    return all(request.get(k) == v for k, v in same.items())


def _jsonable(setup) -> dict:
    """The setup as its data set's request records it (JSON)."""
    return json.loads(json.dumps(dataclasses.asdict(setup)))


def _resuming(state: Resumed | None) -> str:
    """The start of the information line of a resumed acquisition."""
    if state is None:
        return ""
    if state.points_left == 0:
        return f"nothing left to acquire ({state.chunks}/{state.chunks} chunks done): "
    return f"resuming ({state.done}/{state.chunks} chunks done, kept): the "
