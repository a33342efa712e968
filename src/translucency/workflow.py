"""The workflow as functions: acquire, open, fit, evaluate, render, import (``translucency.fit(...)``).

Thin wrappers over the stages (:mod:`translucency.acquire`, :mod:`translucency.fit`,
:mod:`translucency.evaluate`, :mod:`translucency.render`, :mod:`translucency.rig`), each checking its
arguments at the boundary: a mistake is one :class:`~translucency.TranslucencyError` line naming the
Python argument.  ``import translucency`` loads this module on first use of one of its names (the stages
load Dask, Matplotlib and Mitsuba's wrappers).  Units: mm, R_d in mm⁻², linear RGB.
"""

from __future__ import annotations

import dataclasses
import inspect
import os
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ._validate import TranslucencyError, check_option, check_undamaged
from .acquire import PlanarSetup, Volume, load_volume, make_sample
from .acquire import acquire_planar as _acquire_planar
from .acquire.mesh import acquire_mesh as _acquire_mesh
from .acquire.mesh import object_volume
from .evaluate.errors import PlanarErrors, planar_errors
from .evaluate.mesh_errors import MeshErrors, check_same_points, mesh_errors
from .fit import FitResult, fit_mesh, fit_planar
from .io.dataset import PlanarDataset, dataset_identity
from .io.dataset import open_dataset as _open_planar
from .io.mesh import load_mesh
from .io.mesh_dataset import MeshDataset, is_mesh_dataset, open_mesh_dataset
from .io.model_file import load_model, read_header
from .io.outputs import claim_folder
from .render import Camera, parse_light
from .render.camera import view_direction
from .render.figure import figure2
from .render.lights import Placement, place_light
from .render.object import boundary_eta, object_of_model, volume_of_dataset
from .rig import ImportSetup, load_calibration
from .rig import import_images as _import_images
from .rig.shared.hdr import read_hdr

__all__ = [
    "Rendering",
    "acquire_mesh",
    "acquire_planar",
    "evaluate",
    "fit",
    "import_images",
    "make_sample",
    "open_dataset",
    "render",
]


# -- checks at the boundary ----------------------------------------------------------------------
def _path(name: str, value) -> Path:
    """``value`` as a Path, or one line naming the argument."""
    if not isinstance(value, (str, os.PathLike)):
        raise TranslucencyError(f"{name}: expected a path, got {type(value).__name__}")
    return Path(value)


def _count(name: str, value, lo: int = 1) -> int:
    """A whole number ≥ ``lo`` (bools refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TranslucencyError(f"{name}: expected a whole number, got {value!r}")
    return int(check_option(name, int(value), lo=lo))


def _pair(name: str, value, kind):
    """One number for both axes, or two."""
    values = np.atleast_1d(np.asarray(value, dtype=object))
    if values.ndim != 1 or len(values) not in (1, 2):
        raise TranslucencyError(f"{name}: expected one number or two (x, y), got {value!r}")
    return tuple(kind(v) for v in (values if len(values) == 2 else (values[0], values[0])))


def _unknown_options(where: str, options: dict, stage) -> None:
    """Refuse keywords the stage function does not take, naming them."""
    known = set(inspect.signature(stage).parameters)
    unknown = sorted(set(options) - known)
    if unknown:
        raise TranslucencyError(f"{unknown[0]}: not an option of {where}")


def _sample(name: str, value) -> Volume:
    """A :class:`Volume`, or one read from a ``.npz`` path."""
    if isinstance(value, Volume):
        return value
    if isinstance(value, (str, os.PathLike)):
        return load_volume(value)
    raise TranslucencyError(
        f"{name}: expected a Volume or the path of a .npz volume, got {type(value).__name__}"
    )


# -- data sets -----------------------------------------------------------------------------------
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
    path = _path("path", path)
    return open_mesh_dataset(path) if is_mesh_dataset(path) else _open_planar(path)


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
    out = _path("out", out)
    volume = _sample("sample", sample)
    setup = PlanarSetup(
        grid=_pair("grid", grid, lambda v: _count("grid", v)),
        span=_pair("span", span, lambda v: float(check_option("span", v, lo=0))),
        pitch=float(check_option("pitch", pitch, lo=0, open_lo=True)),
        window=float(check_option("window", window, lo=0, open_lo=True)),
        photons=_count("photons", photons),
        seed=_count("seed", seed, lo=0),
        theta_inc_deg=float(check_option("angle", angle, lo=0, hi=90, open_hi=True)),
        index_matched=bool(index_matched),
        chunk_points=_count("chunk_points", chunk_points),
        dtype=dtype,
    )
    inputs = [sample] if isinstance(sample, (str, os.PathLike)) else []
    return _acquire_planar(
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
    out = _path("out", out)
    inputs = []
    if isinstance(mesh, (str, os.PathLike)):
        inputs.append(mesh)
        mesh = load_mesh(mesh, scale_mm=scale_mm, up=up)
    elif not hasattr(mesh, "vertices") or not hasattr(mesh, "faces"):
        raise TranslucencyError(f"mesh: expected a trimesh.Trimesh or a mesh file, got {type(mesh).__name__}")
    if isinstance(sample, str) and Path(sample).suffix != ".npz":
        check_option("voxel_mm", voxel_mm, lo=0, open_lo=True)
        check_option("g", g, lo=-1, hi=1, open_lo=True, open_hi=True)
        volume = object_volume(sample, mesh, float(voxel_mm), g=float(g), seed=_count("seed", seed, lo=0))
    else:
        volume = _sample("sample", sample)
        if not isinstance(sample, Volume):
            inputs.append(sample)
    _acquire_mesh(
        mesh,
        volume,
        out,
        n_points=_count("points", points),
        photons=_count("photons", photons),
        seed=_count("seed", seed, lo=0),
        chunk_points=_count("chunk_points", chunk_points),
        index_matched=bool(index_matched),
        overwrite=overwrite,
        inputs=inputs,
        progress=progress,
        scheduler=scheduler,
    )
    return open_mesh_dataset(out)


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
    folder, out = _path("folder", folder), _path("out", out)
    if isinstance(calibration, (str, os.PathLike)):
        calibration = load_calibration(calibration)
    inputs = [folder] + ([positions] if isinstance(positions, (str, os.PathLike)) else [])
    return _import_images(
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


# -- fitting and evaluation ----------------------------------------------------------------------
def fit(
    dataset,
    model: str = "iso",
    *,
    n_terms: int = 3,
    colour: str | None = None,
    max_rounds: int = 3,
    exclusion_mm: float | None = None,
    alpha_radius: float | None = None,
    progress: Callable[[int, int, str], None] | None = None,
    scheduler: str | None = "threads",
    **options,
) -> FitResult:
    """Fit a model family per incident point, with the modulation texture α, to a planar or mesh data set.

    Wraps :func:`translucency.fit.fit_planar` or :func:`translucency.fit.fit_mesh`, whichever
    ``dataset`` is (``translucency fit``).

    Parameters
    ----------
    dataset : PlanarDataset, MeshDataset or path
        The measurement (:func:`open_dataset`).
    model : {"iso", "aniso", "dipole", "burley", "pbd", "ddipole"}
        The family: the paper's isotropic or anisotropic sum of exponentials, or a baseline
        (meshes: iso, dipole, burley).
    n_terms : int or "auto"
        Exponential terms per profile (1–4); ``"auto"`` chooses by held-out error (planar data).
    colour : {"shared", "per-channel"}, optional
        One fall-off scaled per channel (the paper's), or one per channel; default per-channel on
        planar data, shared on meshes.
    max_rounds : int
        Most alternation rounds (parameters, then α).
    exclusion_mm : float, optional
        Pixels (vertices) closer than this to x_i are ignored; default one pixel (half an edge).
    alpha_radius : float, optional
        Pool α's statistics over this distance, mm (sparse or noisy data).
    progress : callable(done, total, message), optional
    scheduler : str, optional
        ``"threads"``, ``"local:N"`` or ``"tcp://HOST:PORT"``; the fit is the same.
    **options
        Further options of the stage function (``n_directions``, ``weighting``, ``chunk_points``, …).

    Returns
    -------
    FitResult
        ``.model`` (with its α), ``.flagged`` points, ``.history`` (Φ per round), ``.options``.

    Raises
    ------
    TranslucencyError
        A bad option (named) or a damaged data set.

    Examples
    --------
    >>> import translucency as tl
    >>> result = tl.fit(tl.data.default_dataset(), "iso", n_terms=3)  # doctest: +SKIP
    >>> result.model.n_points  # doctest: +SKIP
    1024
    """
    if isinstance(dataset, (str, os.PathLike)):
        dataset = open_dataset(dataset)
    if not isinstance(dataset, (PlanarDataset, MeshDataset)):
        raise TranslucencyError(f"dataset: expected a data set or its path, got {type(dataset).__name__}")
    if not (n_terms == "auto" or isinstance(n_terms, (int, np.integer)) and not isinstance(n_terms, bool)):
        raise TranslucencyError(f"n_terms: expected a whole number or 'auto', got {n_terms!r}")
    max_rounds = _count("max_rounds", max_rounds)
    check_option("exclusion_mm", exclusion_mm, lo=0)
    check_option("alpha_radius", alpha_radius, lo=0)
    check_undamaged(dataset)
    common = dict(
        n_terms=n_terms,
        exclusion_mm=exclusion_mm,
        max_rounds=max_rounds,
        alpha_radius=alpha_radius,
        progress=progress,
        scheduler=scheduler,
        **options,
    )
    if colour is not None:
        common["colour"] = colour
    if isinstance(dataset, MeshDataset):
        _unknown_options("fit on a mesh data set", options, fit_mesh)
        return fit_mesh(dataset.path, model, **common)
    _unknown_options("fit on a planar data set", options, fit_planar)
    return fit_planar(dataset, model, **common)


def _model_and_record(name: str, model) -> tuple[object, dict]:
    """(model, the fit's record) of a FitResult, a model file or a model."""
    if isinstance(model, FitResult):
        return model.model, {
            "flagged_points": np.flatnonzero(model.flagged).tolist(),
            "fit": model.options,
            "acquisition": model.acquisition,
        }
    if isinstance(model, (str, os.PathLike)):
        meta = read_header(model).get("meta", {})
        return load_model(model), meta if isinstance(meta, dict) else {}
    if not all(hasattr(model, a) for a in ("alpha", "n_points", "geometry")):
        raise TranslucencyError(
            f"{name}: expected a model, a FitResult or a model file, got {type(model).__name__}"
        )
    return model, {}


def evaluate(
    model,
    dataset,
    *,
    truth=None,
    flagged=None,
    exclusion_mm: float | None = None,
    scheduler: str | None = "threads",
) -> PlanarErrors | MeshErrors:
    """Relative L2 errors of a fitted model on its data set, or on an independent truth.

    A planar model on a planar data set: :func:`translucency.evaluate.errors.planar_errors`; a per-vertex
    model on a mesh data set: :func:`translucency.evaluate.mesh_errors.mesh_errors` (the numbers of
    ``translucency evaluate``; the reports: :func:`translucency.evaluate.report.write_report`,
    :func:`translucency.evaluate.mesh_report.write_mesh_report`).

    Parameters
    ----------
    model : FitResult, ReflectanceModel or path
        The fit (its flagged points and exclusion radius are used), a model, or a model file (the fit's
        record in it is used).
    dataset : PlanarDataset, MeshDataset or path
        The data set the model was fitted to.
    truth : PlanarDataset, MeshDataset or path, optional
        An independent acquisition of the same incident points (another photon seed, usually more
        photons; on a mesh the same mesh and incident vertices): the errors are then held out, against
        the material rather than the fitted noise.
    flagged : array of bool, optional
        Points to leave out (default: those the fit flagged).
    exclusion_mm : float, optional
        Pairs closer than this are left out (default: the fit's, else one pixel / half the mean edge).
    scheduler : str, optional
        Where the chunks of a planar evaluation run; the errors are the same.

    Returns
    -------
    PlanarErrors or MeshErrors
        ``rel_l2`` (overall), ``bands`` (near < 1 mm, mid 1–4 mm, far > 4 mm), ``noise`` (the
        reference's noise floor), ``energy``, ``beyond_noise`` and the errors per point (and per pixel
        or per vertex).

    Raises
    ------
    TranslucencyError
        A planar model with a mesh data set or the reverse, a model of other incident points, or a
        truth of other incident points.

    Examples
    --------
    >>> import translucency as tl
    >>> data = tl.data.default_dataset()
    >>> errors = tl.evaluate(tl.fit(data), data, truth=tl.data.default_truth())  # doctest: +SKIP
    >>> round(errors.rel_l2, 3)  # doctest: +SKIP
    0.103
    """
    fitted, record = _model_and_record("model", model)
    data = open_dataset(dataset) if isinstance(dataset, (str, os.PathLike)) else dataset
    if not isinstance(data, (PlanarDataset, MeshDataset)):
        raise TranslucencyError(f"dataset: expected a data set or its path, got {type(data).__name__}")
    geometry = getattr(fitted, "geometry", "planar")
    wanted = "mesh" if isinstance(data, MeshDataset) else "planar"
    if geometry != wanted:
        raise TranslucencyError(
            f"model: a {'per-vertex' if geometry == 'mesh' else 'planar'} model and a {wanted} data set; "
            "evaluate takes a planar model with a planar data set, or a per-vertex model with a mesh data set"
        )
    reference = data
    if truth is not None:
        reference = open_dataset(truth) if isinstance(truth, (str, os.PathLike)) else truth
        if not isinstance(reference, type(data)):
            raise TranslucencyError(
                f"truth: expected a {wanted} data set (as dataset) or its path, "
                f"got {type(reference).__name__}"
            )
        if isinstance(data, MeshDataset):
            check_same_points(data, reference)
        if dataset_identity(reference.header) != dataset_identity(data.header):
            warnings.warn(
                f"truth {reference.path}: measured another sample than {data.path}; "
                "the errors compare two materials",
                stacklevel=2,
            )
    if flagged is None:
        flagged = np.zeros(fitted.n_points, bool)
        flagged[np.asarray(record.get("flagged_points", []), dtype=int)] = True
    if exclusion_mm is None:
        exclusion_mm = (record.get("fit") or {}).get("exclusion_mm")
    check_option("exclusion_mm", exclusion_mm, lo=0)
    if isinstance(data, MeshDataset):
        return mesh_errors(fitted, reference, flagged=flagged, exclusion_mm=exclusion_mm)
    return planar_errors(fitted, reference, flagged=flagged, exclusion_mm=exclusion_mm, scheduler=scheduler)


# -- rendering -----------------------------------------------------------------------------------
@dataclasses.dataclass
class Rendering:
    """What :func:`render` made: our picture, the reference (if asked for), the numbers, the folder."""

    picture: np.ndarray  # (H, W, 3) linear radiance, our model's
    reference: np.ndarray | None  # (H, W, 3) Mitsuba volpath of the filling, or None
    numbers: dict  # render.json: timings, and with a reference FLIP, relative RMSE, regions
    folder: Path | None  # where ours.exr/.png (and the reference, render.png) are; None: not kept


def render(
    model,
    out=None,
    *,
    light="point:60,-80,120,2e4",
    view=(1.0, -1.6, 0.7),
    size=(320, 240),
    reference: bool = False,
    spp: int = 32,
    radius: float | None = None,
    overwrite: bool = False,
    progress: Callable[[int, int, str], None] | None = None,
) -> Rendering:
    """Relight a fitted object under a light: irradiance per vertex, sparse transport, a Mitsuba picture.

    Wraps :func:`translucency.render.figure.figure2` (``translucency render``).

    Parameters
    ----------
    model : FitResult, ReflectanceModel or path
        A per-vertex model (a fit on a mesh data set) that carries its mesh.
    out : str or Path, optional
        Folder for ``ours.exr/.png`` (and ``reference.exr/.png``, ``render.png``, ``render.json``);
        default: none kept, the pictures are only returned.
    light : str or light
        ``point:x,y,z[,I]``, ``directional:dx,dy,dz[,E]``, ``spot:…``, ``env:L``, ``env:MAP.exr``
        (:func:`translucency.render.parse_light`), or a light object (``PointLight``, …).
    view : (float, float, float)
        Camera direction from the object's centre.
    size : (int, int)
        Width and height in pixels.
    reference : bool
        Also path-trace the reference (Mitsuba volpath of the generated filling) and compare.
    spp : int
        Samples per pixel of each of the reference's two renders.
    radius : float, optional
        Near radius of the transport, mm (default: the 99 % energy radius, or less where the pairs
        would not fit).
    overwrite : bool
        Replace an earlier output folder of translucency at ``out`` (never anything else).
    progress : callable(done, total, step), optional

    Returns
    -------
    Rendering

    Examples
    --------
    >>> import translucency as tl
    >>> pic = tl.render("pig_iso.model.zip", size=(160, 120))  # doctest: +SKIP
    >>> pic.picture.shape  # doctest: +SKIP
    (120, 160, 3)
    """
    check_option("spp", _count("spp", spp), lo=1)
    check_option("radius", radius, lo=1e-6, hi=1e9)
    size = tuple(_count("size", v) for v in np.atleast_1d(size))
    if len(size) != 2:
        raise TranslucencyError(f"size: expected (width, height), got {size!r}")
    for v in size:
        check_option("size", v, hi=16384)
    fitted, record = _model_and_record("model", model)
    if getattr(fitted, "geometry", None) != "mesh":
        raise TranslucencyError("model: a planar model; render needs a per-vertex model of a mesh data set")
    mesh, acquisition = object_of_model(fitted, {"meta": record})
    direction = view_direction(view)
    lit = place_light(parse_light(light) if isinstance(light, str) else light, Placement.of(mesh, direction))
    if not hasattr(lit, "emitter_dict"):
        raise TranslucencyError(f"light: expected a light or its text (point:x,y,z,I …), got {light!r}")
    camera = Camera.looking_at(mesh, direction, *size)
    volume = volume_of_dataset(mesh, acquisition) if reference else None
    inputs = [model] if isinstance(model, (str, os.PathLike)) else []
    with tempfile.TemporaryDirectory(prefix="translucency-render-") as scratch:
        folder = claim_folder(_path("out", out), overwrite=overwrite, inputs=inputs) if out else Path(scratch)
        numbers = figure2(
            fitted,
            mesh,
            lit,
            folder,
            volume=volume,
            camera=camera,
            spp_reference=spp,
            radius=radius,
            eta=boundary_eta(acquisition),
            progress=progress,
        )
        picture = read_hdr(folder / "ours.exr")
        ref = read_hdr(folder / "reference.exr") if reference else None
    return Rendering(picture, ref, numbers, folder if out else None)
