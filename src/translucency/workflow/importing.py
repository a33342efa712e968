"""A lab's photographs as functions: HDR photographs of a scanned laser spot into a planar data set
(:func:`import_images`), multi-view photographs of a laser stepped over an object into a mesh data set
(:func:`import_object`).

``translucency import images|object`` are these functions: the arguments checked at the boundary, the
output claimed (an unfinished import of the same inputs resumes; Ctrl-C keeps the chunks done), the import
and the summary the command prints.  Units: mm, R_d in mm⁻².
"""

from __future__ import annotations

import copy
import dataclasses
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .. import resources
from .._extras import require
from .._validate import TranslucencyError, check_option
from ..cluster import parse_scheduler
from ..io.dataset import PlanarDataset, open_dataset
from ..io.mesh import load_mesh
from ..io.mesh_dataset import MeshDataset, open_mesh_dataset
from ..io.outputs import claim_output
from ..resources.run import Reporter, Run, kept_chunks
from ..rig import ImportSetup, load_calibration
from ..rig import import_images as import_planar
from ..rig.object.importer import import_object as import_mesh
from ..rig.object.setup import read_object_rig
from ..rig.planar.frames import image_shape
from ..rig.planar.positions import read_positions
from ._arguments import as_path, whole_number

__all__ = ["EXIT_LAWS", "import_images", "import_object"]

#: how an object's radiance becomes exitance (``import_object``'s ``exit_law``)
EXIT_LAWS = ("from-views", "dielectric", "lambertian", "walk")


def import_images(
    folder,
    positions,
    calibration,
    out,
    *,
    overwrite: bool = False,
    extra_cameras=(),
    gain: float | None = None,
    progress: Callable[[int, int], None] | None = None,
    scheduler: str | None = "threads",
    max_memory: str | int | None = None,
    reporter: Reporter | None = None,
    **setup,
) -> PlanarDataset:
    """A real rig's HDR photographs of a scanned laser spot → a planar data set.

    ``translucency import images`` is this function (:func:`translucency.rig.import_images` under the
    run's checks and resuming).

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
    overwrite : bool
        Replace a data set of translucency made from other inputs (never anything else).
    extra_cameras : sequence of (folder, positions, Calibration or path)
        Further cameras photographing the same laser positions, averaged onto the same windows
        (``views`` still works for one release, with a DeprecationWarning).
    gain : float, optional
        Pixel value per unit exitance (W/mm²) per second: replaces every calibration's ``scale``
        (``scale`` still works for one release, with a DeprecationWarning).
    progress : callable(done, total), optional
    scheduler : str, optional
        ``"threads"``, ``"local:N"`` or ``"tcp://HOST:PORT"``; the data are the same bit for bit.
    max_memory : str or int, optional
        Most memory the import may use; a larger estimate (a chunk of photographs and of windows) is
        refused before any work.
    reporter : Reporter, optional
        Hears the run's information lines (default: silent).
    **setup
        Fields of :class:`translucency.rig.ImportSetup`: ``pitch``, ``window``, ``supersample``,
        ``specular_radius``, ``dilate``, ``floor``, ``sample_size``, ``eta``, ``chunk_points``,
        ``dtype``, ``beam_rms``.

    Returns
    -------
    PlanarDataset
        With ``.summary``: the import's numbers (points, windows, the marked points' fit).

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
    >>> ds.window, ds.summary["points"]
    ((5, 5), 1)
    """
    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    setup = _import_setup(setup)
    check_option("gain", gain, lo=0, open_lo=True)
    folder, out = as_path("folder", folder), as_path("out", out)
    views = [_view(v) for v in extra_cameras]
    run = Run("import images", max_memory=max_memory, reporter=reporter)
    need = _planar_need(folder, positions, views, setup)
    if need is not None:  # (None: an input the importer names in its own words below)
        run.check(need, out)
    files = [p for p in (positions, calibration, *(p for v in views for p in v)) if _a_path(p)]
    claim_output(out, "planar data set", overwrite=overwrite, inputs=[folder, *files], reuse=True)
    calib = _calibration(calibration, gain)
    others = [
        (v_folder, v_positions, _calibration(v_calib, gain)) for v_folder, v_positions, v_calib in views
    ]
    run.kept = lambda: kept_chunks(out, open_dataset)  # Ctrl-C: the chunks kept, and how to resume
    cal_files = [c for c in (calibration, *(v[2] for v in views)) if _a_path(c)]
    ds = import_planar(
        folder,
        positions,
        calib,
        out,
        setup,
        overwrite=overwrite,
        inputs=cal_files,
        progress=progress,
        views=others,
        scheduler=scheduler,
    )
    ds.summary = run.summary(
        {
            "command": "import images",
            "out": out,
            "points": ds.n_points,
            "window_pixels": ds.window,
            "pitch": ds.pitch,
            "rms_px": calib.source.get("rms_px"),  # the marked points' fit, if the calibration has them
            "seconds": run.seconds(),
        }
    )
    return ds


def _planar_need(folder: Path, positions, views: list, setup: ImportSetup):
    """The memory and disk of a planar import, from its first photograph's size and the frames of a laser
    position (every camera's); None where an input cannot be read (the importer says why)."""
    try:
        shots = list(positions) if isinstance(positions, list | tuple) else read_positions(positions, folder)
        frames = max(len(s.files) for s in shots)
        for v_folder, v_positions, _ in views:
            listed = isinstance(v_positions, list | tuple)
            v_shots = list(v_positions) if listed else read_positions(v_positions, v_folder)
            frames += max(len(s.files) for s in v_shots)
        H, W = image_shape(shots[0])[:2]
    except (TranslucencyError, OSError, ValueError):
        return None
    n = setup.window_pixels()
    return resources.memory.photograph_import(
        positions=len(shots), chunk=setup.chunk_points, images=frames, pixels=H * W, cells=n * n
    )


def _a_path(value) -> bool:
    return isinstance(value, (str, os.PathLike))


def _object_need(setup, chunk_points: int):
    """The memory and disk of an object import: a chunk's photographs (every camera's frames of a shot,
    at the largest camera's size) and its R_d per vertex."""
    images = max((sum(len(f) for f in shot.frames.values()) for shot in setup.shots), default=0)
    pixels = max((c.width * c.height for c in setup.cameras), default=0)
    vertices = len(load_mesh(setup.mesh_file, scale_mm=setup.scale_mm, up=setup.up).vertices)
    return resources.memory.photograph_import(
        positions=len(setup.shots),
        chunk=chunk_points,
        images=images,
        pixels=pixels,
        cells=vertices,
        mitsuba=True,  # the cameras' rays traced on the mesh
    )


def _import_setup(setup: dict) -> ImportSetup:
    """The fields of :class:`ImportSetup`, checked."""
    fields = {f.name for f in dataclasses.fields(ImportSetup)}
    unknown = sorted(set(setup) - fields)
    if unknown:
        raise TranslucencyError(f"{unknown[0]}: not a field of ImportSetup ({', '.join(sorted(fields))})")
    for name in ("pitch", "window", "eta"):
        check_option(name, setup.get(name), lo=0, open_lo=True)
    for name in ("specular_radius", "dilate", "beam_rms"):
        check_option(name, setup.get(name), lo=0)
    check_option("supersample", setup.get("supersample"), lo=1, hi=16)
    if setup.get("chunk_points") is not None:
        whole_number("chunk_points", setup["chunk_points"])
    if setup.get("sample_size") is not None:
        setup = {**setup, "sample_size": _sample_size(setup["sample_size"])}
    return ImportSetup(**setup)


def _sample_size(value) -> tuple[float, float]:
    """The sample's (width, height) in mm, from two numbers or their text ``"20,20"``."""
    try:
        size = tuple(float(v) for v in (value.split(",") if isinstance(value, str) else value))
    except (TypeError, ValueError):
        size = ()
    if len(size) != 2 or not all(np.isfinite(v) and v > 0 for v in size):
        raise TranslucencyError(f"sample_size: expected width,height in mm, got {value!r}")
    return size


def _view(view) -> tuple:
    """A further camera's (folder, positions, calibration), its paths checked to exist."""
    try:
        folder, positions, calibration = view
    except (TypeError, ValueError):
        raise TranslucencyError(
            f"extra_cameras: expected (folder, positions, calibration), got {view!r}"
        ) from None
    for what, value in (("folder", folder), ("positions", positions), ("calibration", calibration)):
        if isinstance(value, (str, os.PathLike)) and not Path(value).exists():
            raise TranslucencyError(f"extra_cameras: {what} {value}: no such file or folder")
    return Path(folder), positions, calibration


def _calibration(calibration, gain: float | None):
    """A Calibration (read from its file), with ``gain`` in place of its ``scale`` when given (a caller's
    object is copied, not changed)."""
    if isinstance(calibration, (str, os.PathLike)):
        if not Path(calibration).is_file():
            raise TranslucencyError(f"calibration {calibration}: no such file")
        calibration = load_calibration(calibration)
    elif gain is not None:
        calibration = copy.copy(calibration)
    if gain is not None:
        calibration.scale = gain
    return calibration


def _law_used(info: dict) -> dict:
    """The exit law of an object import as its summary states it: with ``walk``, also the shots (of this
    run's chunks) converted with the walks' law — a shot without a near peak to fit keeps π L."""
    law = dict(info["exit_law"])
    if law["law"] == "walk":
        law["walked_shots"] = sorted(set(info["walked_shots"]))
    return law


def import_object(
    rig,
    out,
    *,
    exit_law: str | None = None,
    chunk_points: int = 8,
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
    max_memory: str | int | None = None,
    reporter: Reporter | None = None,
) -> MeshDataset:
    """A lab's multi-view HDR photographs of a laser stepped over a scanned object → a mesh data set.

    ``translucency import object`` is this function (:func:`translucency.rig.object.importer.import_object`
    under the run's checks and resuming).  The data set is read by :func:`translucency.fit_model`,
    :func:`translucency.render_model` and the report as one of :func:`acquire_mesh`'s.

    Parameters
    ----------
    rig : path
        The rig file ``object.json`` (or its folder): mesh, cameras, shots (docs/reference/object-rig.md).
    out : str or Path
        The mesh data set folder; an unfinished import of the same inputs resumes.
    exit_law : {"from-views", "dielectric", "lambertian", "walk"}, optional
        Radiance to exitance: a law estimated from vertices two cameras see, the boundary's
        F_t/(1 - F_dr), π L, or the transport's own law per cell and camera from photon walks on the scan
        at the material the near peak fitted to each shot (:mod:`translucency.rig.object.walk_law`; a
        shot without a near peak to fit keeps π L); default the rig file's.
    chunk_points : int
        Laser shots per chunk (the unit of resuming; memory holds one chunk of images).
    overwrite : bool
        Replace a data set of translucency made from other inputs (never anything else).
    progress : callable(done, total), optional
    max_memory : str or int, optional
        Most memory the import may use; a larger estimate (a chunk of photographs, every camera's, and
        of R_d per vertex) is refused before any work.
    reporter : Reporter, optional
        Hears the run's progress (default: silent).

    Returns
    -------
    MeshDataset
        With ``.summary``: cameras (their reprojection errors), the exit law, flags, energy, throughput.

    Examples
    --------
    A ball photographed by a virtual rig (:func:`acquire_object_photographs`, its boundary a dielectric of
    η = 1.3) and imported with the matching exit law (about two minutes, so not run here):

    >>> import tempfile, trimesh
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> folder = Path(tempfile.mkdtemp())
    >>> ball = trimesh.creation.icosphere(2, radius=6.0)
    >>> shots = tl.acquire_object_photographs(ball, folder / "rig", points=2, cameras=3, resolution=(32, 32),
    ...                                       spp=4, eta=1.3)  # doctest: +SKIP
    >>> ds = tl.import_object(shots.folder / "object.json", folder / "ball.zarr",
    ...                       exit_law="dielectric")  # doctest: +SKIP
    >>> ds.n_points, ds.summary["exit_law"]["law"]  # doctest: +SKIP
    (2, 'dielectric')
    """
    require("rig")  # the cameras' projection (OpenCV): a missing extra is one line before any work
    chunk_points = whole_number("chunk_points", chunk_points)
    if exit_law is not None and exit_law not in EXIT_LAWS:
        raise TranslucencyError(f"exit_law: one of {', '.join(EXIT_LAWS)}; got {exit_law!r}")
    out = as_path("out", out)
    setup = read_object_rig(rig)  # a bad rig file: one line before the output is judged
    run = Run("import object", max_memory=max_memory, reporter=reporter)
    run.check(_object_need(setup, chunk_points), out)
    claim_output(out, "mesh data set", overwrite=overwrite, inputs=setup.files, reuse=True)
    run.kept = lambda: kept_chunks(out, open_mesh_dataset)  # Ctrl-C: the chunks kept, and how to resume
    with run.reporter.progress("import", len(setup.shots)) as update:
        update(item="shots")

        def step(done: int, total: int) -> None:
            update(completed=done)
            if progress is not None:
                progress(done, total)

        info = import_mesh(
            setup.path, out, chunk_points=chunk_points, overwrite=overwrite, exit_law=exit_law, progress=step
        )
    ds = open_mesh_dataset(out)
    mb = info["bytes_read"] / 2**20
    ds.summary = run.summary(
        {
            "command": "import object",
            "out": out,
            "points": ds.n_points,
            "vertices": int(ds.header["n_vertices"]),
            "cameras": info["cameras"],
            "exit_law": _law_used(info),
            "flags": info["flags"],
            "saturated_views": info["saturated_views"],
            "near_peak": info["near_peak"],
            "rays_per_pixel": info["rays_per_pixel"],
            "energy": info["energy"],
            "energy_sigma": info["energy_sigma"],
            "beam_polar_deg": info["beam_polar_deg"],
            "images_MB": mb,
            "seconds": info["seconds"],
            "throughput_MB_s": mb / max(info["seconds"], 1e-9),
        }
    )
    return ds
