"""A virtual rig's photographs as functions: a planar sample (:func:`acquire_photographs`) or an object
(:func:`acquire_object_photographs`) photographed by Mitsuba as a lab would hand them over — HDR images,
the laser's positions, the cameras' calibration — the inputs of ``translucency import images|object``.

``translucency acquire photographs|object-photographs`` are these functions.  Units: mm, σ in mm⁻¹,
radiance per unit of the laser's power.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import resources
from .._extras import require
from .._validate import TranslucencyError, check_option
from ..acquire import PlanarSetup, load_volume, make_sample
from ..acquire.mesh import check_filling, object_volume
from ..resources.run import Reporter, Run
from ..rig.object.photographs import LaserBeam, photograph_object
from ..rig.planar.photographs import VirtualCamera, photograph_sample
from ._arguments import (
    UP_AXES,
    as_path,
    mesh_file_of,
    object_of,
    sample_of,
    slab_of,
    whole_number,
)

__all__ = [
    "FULL",
    "IMAGE_FORMATS",
    "PREVIEW",
    "Photographs",
    "acquire_object_photographs",
    "acquire_photographs",
]

#: the image formats of a virtual rig's photographs
IMAGE_FORMATS = ("pfm", "exr")
#: a virtual object rig's settings where none are given: :data:`FULL`, or with ``preview`` (``acquire
#: object-photographs --preview``) a rehearsal — a first imported object in about two minutes on 2 cores
#: (photographs and ``import object``, the 100 mm example cow in skin) against about ten; noisy
#: photographs, a coarse filling: for trying the chain, not for a model to trust
FULL = {"points": 8, "cameras": 6, "resolution": (128, 128), "spp": 64, "voxel_mm": 0.5}
PREVIEW = {"points": 4, "cameras": 4, "resolution": (48, 36), "spp": 4, "voxel_mm": 1.0}


@dataclass
class Photographs:
    """What :func:`acquire_photographs` or :func:`acquire_object_photographs` wrote: the folder a lab would
    hand over, the rig's record of it and the run's summary.

    Examples
    --------
    A small slab of skin photographed at one incident point (:func:`acquire_photographs`):

    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> shots = tl.acquire_photographs("homogeneous:skin1", Path(tempfile.mkdtemp()) / "shots", grid=1,
    ...                                size=(8, 8, 3), voxel_mm=1.0, spp=8)
    >>> shots.folder.name, sorted(shots.record)
    ('shots', ['homography', 'marked', 'power', 'rms_px'])

    An object's (:func:`acquire_object_photographs`) holds ``object.json`` and a ``record`` of its
    ``incident`` vertices and true ``cameras``.
    """

    folder: Path
    record: dict  # a sample's: homography (true), marked, rms_px, power; an object's: incident, cameras
    summary: dict  # the numbers ``translucency acquire photographs|object-photographs --json`` prints


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
    max_memory: str | int | None = None,
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
    max_memory : str or int, optional
        Most memory the photographs may use; a larger estimate (the volume, a render) is refused before
        any is taken.
    reporter : Reporter, optional
        Hears the run's information line (default: silent).

    Returns
    -------
    Photographs
        ``.folder``, ``.record`` (the true homography, the marked points' ``rms_px``, …), ``.summary``.

    Examples
    --------
    One incident point on a small slab of skin, photographed and imported as a data set:

    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> folder = Path(tempfile.mkdtemp())
    >>> shots = tl.acquire_photographs("homogeneous:skin1", folder / "shots", grid=1, size=(8, 8, 3),
    ...                                voxel_mm=1.0, spp=8)
    >>> sorted(p.name for p in shots.folder.glob("*.csv")), (shots.folder / "calibration.json").is_file()
    (['positions.csv'], True)
    >>> ds = tl.import_images(shots.folder, shots.folder / "positions.csv",
    ...                       shots.folder / "calibration.json", folder / "d.zarr", gain=1e5)
    >>> ds.n_points
    1
    """
    require("rig")  # the photographs' calibration (OpenCV): a missing extra is one line before any work
    grid = int(check_option("grid", whole_number("grid", grid), hi=64))
    spp, seed = whole_number("spp", spp), whole_number("seed", seed, lo=0)
    fov = float(check_option("fov", fov, lo=1, hi=120))
    resolution = _resolution(resolution)
    image_format = _image_format(image_format)
    size, voxel_mm, _ = slab_of(size, voxel_mm, 0.0)
    out = as_path("out", out)
    run = Run("acquire photographs", max_memory=max_memory, reporter=reporter)
    name, volume, path = sample_of(sample)
    run.claim_folder(out, overwrite=overwrite, inputs=[path])
    if name is not None:
        volume = make_sample(name, size, voxel_mm, seed=seed)
    elif path is not None:
        volume = load_volume(path)
    W, H, _ = volume.size_mm
    setup = PlanarSetup(grid=(grid, grid), span=(span, span), pitch=0.25, window=min(W, H) / 2)
    setup.check(volume)
    x_i = setup.incident_points(volume)
    W_px, H_px = resolution
    need = resources.memory.photographs(
        voxels=float(np.prod(volume.sigma_s.shape[:3])), width=W_px, height=H_px, spp=spp, files=len(x_i) + 3
    )
    run.check(need, out)  # the shots, the marked points', dark and flat frames
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
    voxel_mm: float | None = None,
    points: int | None = None,
    cameras: int | None = None,
    resolution=None,
    spp: int | None = None,
    preview: bool = False,
    beam_mm: float = 0.3,
    eta: float | None = None,
    checkerboards: bool = False,
    exposures: str = "brackets",
    seed: int = 0,
    image_format: str = "pfm",
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
    max_memory: str | int | None = None,
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
    points, cameras : int, optional
        Laser positions (a farthest-point sample of the vertices) and cameras (1–64).
    resolution : (int, int), optional
        Image width and height, pixels (8–8192).
    spp : int, optional
        Samples per pixel of each of the two repeated frames.
    preview : bool
        Where ``voxel_mm``, ``points``, ``cameras``, ``resolution`` or ``spp`` is None, take it from
        :data:`PREVIEW` (a quick rehearsal) instead of :data:`FULL` (8 points, 6 cameras, 128 × 128 px,
        64 spp, 0.5 mm voxels).
    beam_mm : float
        Radius of the laser's spot on the surface, mm.
    eta : float, optional
        The boundary's relative index: 1 index-matched; > 1 a smooth dielectric (the laser enters through
        a window over its spot, :func:`translucency.rig.object.photographs.render_shot`).  Default: the
        filling's own (``Volume.eta``: 1.3 for the generated materials), as in :func:`acquire_mesh`.
    checkerboards : bool
        Give the intrinsics as checkerboard photographs (OpenCV calibrates them on import).
    exposures : {"brackets", "single"}
        Per camera and shot, two repeated long exposures and a short one, or one long exposure with the
        spot clipped (a lab's single exposure: ``import object`` recovers the spot from its ring).
    seed : int
        Random seed of the filling, the renders and the sensor.
    image_format : {"pfm", "exr"}
    overwrite, progress, max_memory, reporter
        As in :func:`acquire_photographs` (``progress(done, total)``: shots photographed).

    Returns
    -------
    Photographs
        ``.folder``, ``.record`` (``incident`` vertices, true ``cameras``, ``seconds``), ``.summary``.

    Examples
    --------
    A ball photographed by three cameras at two laser positions (tens of seconds; the import, ray casting
    every pixel, a minute or more, so neither is run here):

    >>> import tempfile, trimesh
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> folder = Path(tempfile.mkdtemp())
    >>> ball = trimesh.creation.icosphere(2, radius=6.0)
    >>> shots = tl.acquire_object_photographs(ball, folder / "rig", points=2, cameras=3, resolution=(32, 32),
    ...                                       spp=4, eta=1.0)  # doctest: +SKIP
    >>> len(shots.record["incident"]), len(shots.record["cameras"])  # doctest: +SKIP
    (2, 3)
    >>> ds = tl.import_object(shots.folder / "object.json", folder / "ball.zarr")  # doctest: +SKIP
    >>> ds.n_points, ds.summary["exit_law"]["law"]  # doctest: +SKIP
    (2, 'lambertian')

    The package's meshes (:func:`translucency.data.example_path`: ``cow.obj``, ``spot.obj``) are
    photographed the same way, in minutes.
    """
    require("rig")  # the cameras' projection (OpenCV): a missing extra is one line before any work
    settings = PREVIEW if preview else FULL  # where the caller gave None
    voxel_mm, points, cameras, resolution, spp = (
        settings[k] if v is None else v
        for k, v in (("voxel_mm", voxel_mm), ("points", points), ("cameras", cameras),
                     ("resolution", resolution), ("spp", spp))
    )  # fmt: skip
    points = whole_number("points", points)
    cameras = int(check_option("cameras", whole_number("cameras", cameras), hi=64))
    spp, seed = whole_number("spp", spp), whole_number("seed", seed, lo=0)
    beam_mm = float(check_option("beam_mm", beam_mm, lo=0, open_lo=True))
    eta = None if eta is None else float(check_option("eta", eta, lo=1.0))
    voxel_mm = float(check_option("voxel_mm", voxel_mm, lo=0, open_lo=True))
    scale_mm = float(check_option("scale_mm", scale_mm, lo=0, open_lo=True))
    resolution, image_format = _resolution(resolution), _image_format(image_format)
    _check_exposures_and_up(exposures, up)
    out, mesh_file = as_path("out", out), mesh_file_of(mesh)
    run = Run("acquire object-photographs", max_memory=max_memory, reporter=reporter)
    run.claim_folder(out, overwrite=overwrite, inputs=[mesh_file])
    obj = object_of(mesh, mesh_file, scale_mm, up)
    if points > len(obj.vertices):
        raise TranslucencyError(f"points: need 1 to {len(obj.vertices):,} laser positions, got {points:,}")
    volume = object_volume(sample, obj, voxel_mm, seed=seed)
    eta = float(volume.eta) if eta is None else eta
    check_filling(obj, volume)
    _check_object_shots(run, out, obj, volume, points, cameras, resolution, spp, exposures)
    with run.reporter.progress("photograph", points) as update:
        update(item="shots")
        record = photograph_object(
            obj, volume, out, n_points=points, n_cameras=cameras, resolution=resolution, spp=spp, seed=seed,
            beam=LaserBeam(radius_mm=beam_mm), image_format=image_format, checkerboards=bool(checkerboards),
            exposures=exposures, spot_radius_mm=max(0.5, 2 * beam_mm), boundary_eta=eta,
            progress=_shot_steps(update, progress),
        )  # fmt: skip
    summary = {
        "command": "acquire object-photographs",
        "out": out,
        "points": points,
        "cameras": cameras,
        "incident": record["incident"],
        "seconds": record["seconds"],
    }
    return Photographs(out, record, run.summary(summary))


def _check_exposures_and_up(exposures: str, up: str) -> None:
    """Refuse an unknown ``exposures`` or ``up`` (options: before the mesh is read)."""
    if exposures not in ("brackets", "single"):
        raise TranslucencyError(f"exposures: brackets or single, got {exposures!r}")
    if up not in UP_AXES:
        raise TranslucencyError(f"up: expected one of z, y, x, got {up!r}")


def _check_object_shots(run: Run, out: Path, obj, volume, points, cameras, resolution, spp, exposures):
    """The photographs' memory estimate checked against the run's limit, and the run's information line."""
    frames = 3 if exposures == "brackets" else 1  # two long exposures and a short one, or one
    need = resources.memory.photographs(
        voxels=float(np.prod(volume.sigma_s.shape[:3])),
        width=resolution[0],
        height=resolution[1],
        spp=spp,
        files=points * cameras * frames + 2 * cameras,  # the shots, each camera's dark and flat frames
        mesh_elements=len(obj.vertices) + len(obj.faces),
    )
    run.check(need, out)
    run.info(
        f"{points} laser positions x {cameras} cameras x 3 channels x {2 if exposures == 'brackets' else 1} "
        f"frames at {spp} spp "
        f"({resolution[0]} x {resolution[1]} px), mesh of {len(obj.vertices):,} vertices"
    )


def _shot_steps(update, progress: Callable[[int, int], None] | None) -> Callable[[int, int], None]:
    """The photographing's progress: the run's bar, and the caller's ``progress(done, total)`` if given."""

    def step(done: int, total: int) -> None:
        update(completed=done)
        if progress is not None:
            progress(done, total)

    return step
