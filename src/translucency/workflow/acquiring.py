"""Virtual DISCO as functions: a planar sample or an object scanned by photon transport into a data set
(:func:`acquire_planar`, :func:`acquire_mesh`), and a virtual rig's photographs of either, written as a
lab hands them over (:func:`acquire_photographs`, :func:`acquire_object_photographs`).

``translucency acquire planar|mesh|photographs|object-photographs`` are these functions: the arguments
checked at the boundary, the memory and time estimated before the work (refused in one line beyond
``max_memory``), the output claimed (an unfinished acquisition with the same arguments resumes,
:mod:`._resuming`; Ctrl-C keeps the chunks done), the work, and the summary the command prints.
Units: mm, σ in mm⁻¹.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Sequence
from pathlib import Path

from .. import resources
from .._validate import TranslucencyError, check_option
from ..acquire import PlanarSetup, Volume, estimate_seconds, load_volume, make_sample, probe_walk
from ..acquire import acquire_planar as scan_planar
from ..acquire.mesh import UNSCATTERED, check_filling, object_volume
from ..acquire.mesh import acquire_mesh as scan_mesh
from ..acquire.planar import setup_request
from ..angles import ExitBins, Incidence
from ..cluster import parse_scheduler
from ..io.dataset import PlanarDataset, open_dataset
from ..io.mesh_dataset import MeshDataset, open_mesh_dataset
from ..io.outputs import claim_output
from ..resources.run import Reporter, Run, bytes_at, kept_chunks
from ._arguments import (
    UP_AXES,
    as_path,
    mesh_file_of,
    object_of,
    one_or_two,
    sample_of,
    slab_of,
    whole_number,
)
from ._resuming import Resumed, matches, resumable, resuming, to_acquire

__all__ = [
    "acquire_mesh",
    "acquire_planar",
    "make_sample",
]


def acquire_planar(
    sample,
    out,
    *,
    grid=8,
    span=8.0,
    pitch: float = 0.25,
    window: float = 8.0,
    photons: int = 20_000,
    seed: int = 0,
    sample_seed: int | None = None,
    size=(20.0, 20.0, 8.0),
    voxel_mm: float = 0.25,
    g: float = 0.0,
    angle: float = 0.0,
    incidence: Sequence[float] = (),
    azimuths: int = 4,
    exit_bins: int = 0,
    index_matched: bool = False,
    eta: float | None = None,
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
    incidence : sequence of float
        Polar angles (degrees from the normal) of oblique beams besides the normal one, each at
        ``azimuths`` azimuths of the slab's frame (x, y, z) (:class:`translucency.angles.Incidence`;
        ``angle`` stays 0 then); stored as ``R_d_oblique`` and its specular and top-face shares.
    azimuths : int
        Azimuths per ``incidence`` angle.
    exit_bins : int
        Also tally each exit by direction: this many polar bins × 2 halves
        (:class:`translucency.angles.ExitBins`); 0: none.
    index_matched : bool
        No Fresnel reflection at the boundary: ``eta=1``.
    eta : float, optional
        The boundary's relative index of refraction (>= 1; 1: index-matched).  Default: the sample's own
        (``Volume.eta``: 1.3 for the generated materials).
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
    ...                        photons=200)
    >>> ds.n_points, ds.window, ds.summary["complete"]
    (4, (9, 9), True)
    """
    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    out = as_path("out", out)
    eta, index_matched = _boundary(eta, index_matched)
    setup = _planar_setup(grid, span, pitch, window, photons, seed, angle, index_matched, chunk_points, dtype)
    angles, bins = _angle_axes(incidence, azimuths, exit_bins)
    setup = dataclasses.replace(setup, incidence=angles, exit_bins=bins)
    sample_seed = whole_number("sample_seed", seed if sample_seed is None else sample_seed, lo=0)
    size, voxel_mm, g = slab_of(size, voxel_mm, g)
    run = Run("acquire planar", max_memory=max_memory, reporter=reporter)
    name, volume, path = sample_of(sample)

    if name is not None:  # before the sample is generated
        estimate = _planar_estimate(run, out, setup, resources.memory.slab_voxels(size, voxel_mm))
    claim_output(out, "planar data set", overwrite=overwrite, inputs=[path], reuse=True)
    if name is not None:
        volume = make_sample(name, size, voxel_mm, g=g, seed=sample_seed)
    else:
        volume = volume if path is None else load_volume(path)
        estimate = _planar_estimate(run, out, setup, volume.sigma_s.size / 3)
    volume = _with_eta(volume, eta)
    setup.check(volume)
    state = _timed_planar(run, volume, setup, out, estimate)
    P = setup.grid[0] * setup.grid[1]
    with run.work("acquire", total=P, fresh=state is None and bytes_at(out) == 0) as work:
        work.update(completed=P - to_acquire(state, P), item="points")
        steps = _steps(work, progress)
        scan_planar(
            volume, setup, out, overwrite=overwrite, inputs=[path], progress=steps, scheduler=scheduler
        )
    ds = open_dataset(out)
    ds.summary = _planar_summary(run, out, ds, setup)
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


def _planar_estimate(run: Run, out: Path, setup: PlanarSetup, voxels):
    """The planar scan's memory estimate for ``voxels`` voxels, checked against the run's limit."""
    n = resources.memory.planar_acquisition(
        grid=setup.grid,
        pitch=setup.pitch,
        window=setup.window,
        photons=setup.photons,
        chunk=setup.chunk_points,
        voxels=voxels,
        dtype=setup.dtype,
        directions=setup.incidence.count,
        exit_bins=0 if setup.exit_bins is None else setup.exit_bins.count,
    )
    return run.check(n, out, resumed=True)  # a resumed acquisition keeps what is there


def _planar_summary(run: Run, out: Path, ds: PlanarDataset, setup: PlanarSetup) -> dict:
    """The numbers of ``translucency acquire planar --json``."""
    return run.summary(
        {
            "command": "acquire planar",
            "out": out,
            "points": ds.n_points,
            "window_pixels": ds.window,
            "directions": setup.incidence.count,
            "exit_bins": 0 if setup.exit_bins is None else setup.exit_bins.count,
            "photons": setup.photons,
            "seed": setup.seed,
            "complete": ds.complete(),
            "seconds": run.seconds(),
        }
    )


def _timed_planar(run: Run, volume: Volume, setup: PlanarSetup, out: Path, estimate) -> Resumed | None:
    """The planar scan's time estimate (from a probe of the walk on ``volume``), its information line and
    its note for Ctrl-C; the data set it resumes, if any."""
    walk = probe_walk(volume, setup)  # a short trace of this volume: its steps a photon, this machine's speed
    P = setup.grid[0] * setup.grid[1]
    want = setup_request(setup)  # the same setup and the same angle axes (none: none)
    same = lambda request: all(request.get(k) == want.get(k) for k in ("setup", "angles"))  # noqa: E731
    state = resumable(out, open_dataset, same)
    share = 1.0 if state is None else state.points_left / P  # what is left of the work
    D = setup.incidence.count  # photons × directions
    units = resources.timing.planar_acquisition_units(
        points=round(share * P),
        photon_steps=share * D * estimate_seconds(volume, setup, steps_per_second=1.0, probe=walk),
        pixels=round(share * P) * setup.window_pixels() ** 2,
    )
    first = resources.timing.probe_factor("acquire planar", "photon_steps", walk.seconds_per_step)
    timing = run.time(units, (first, "from a probe of the walk on this sample"))
    run.kept = lambda: kept_chunks(out, open_dataset)
    run.info(
        f"{resuming(state)}{round(share * P)} incident points x {setup.photons:,} photons x 3 channels"
        f"{f' x {D} directions' if D > 1 else ''}"
        f"{f' ({setup.exit_bins.count} exit bins)' if setup.exit_bins else ''} on a "
        f"{' x '.join(f'{v:g}' for v in volume.size_mm)} mm slab; time {timing.text()}, "
        f"memory ~{estimate.memory / 2**20:,.0f} MiB",
    )
    return state


def acquire_mesh(mesh, out, sample="marble", *, voxel_mm: float = 0.5, g: float = 0.0, points: int = 64,
    photons: int = 20_000, seed: int = 0, sample_seed: int | None = None, chunk_points: int = 8,
    index_matched: bool = False, eta: float | None = None, reentry: bool = True, unscattered: str = "apart",
    incidence: Sequence[float] = (), azimuths: int = 4, exit_bins: int = 0, scale_mm: float = 1.0,
    up: str = "z", overwrite: bool = False, progress: Callable[[int, int], None] | None = None,
    scheduler: str | None = "threads", max_memory: str | int | None = None, reporter: Reporter | None = None,
) -> MeshDataset:  # fmt: skip
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
        bounding box at ``voxel_mm`` with ``g`` and ``sample_seed``, a Volume, or a ``.npz`` volume over
        that box.
    points : int
        Incident points (a farthest-point sample of the vertices).
    photons, seed, chunk_points : int
        Photons per point and channel, their random seed, incident points per chunk.
    sample_seed : int, optional
        Seed of a generated filling (default ``seed``): the same ``sample_seed`` with another ``seed`` is
        a held-out truth of the same object.
    index_matched : bool
        No Fresnel reflection at the surface: ``eta=1``.
    eta : float, optional
        The surface's relative index of refraction (>= 1; 1: index-matched).  Default: the filling's own
        (``Volume.eta``: 1.3 for the generated materials).
    reentry : bool
        Light that leaves one part through the air into another walks on there, tallied where it finally
        escapes (as a photograph sees it); ``False``: tallied where it first left.
    unscattered : {"apart", "counted"}
        Light that leaves without scattering (a beam crossing a thin part, seen only head-on): kept apart
        from R_d, its fraction stored as ``unscattered`` (the default), or counted in R_d as the data sets
        made before (:func:`translucency.acquire.mesh.acquire_mesh`).
    incidence : sequence of float
        Polar angles (degrees from the normal) of oblique beams besides the normal one, each at
        ``azimuths`` azimuths of the incident point's tangent frame (:class:`translucency.angles.Incidence`);
        default none: the paper's normal beams.  Cost: photons × (1 + len(incidence) × azimuths).
    exit_bins : int
        0 (default) or the number of polar exit bins; each exit is also counted by its direction in
        ``exit_bins`` × 2 bins (:class:`translucency.angles.ExitBins`).
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
    A ball of 4 mm radius (a mesh of trimesh's; the package's ``spot.obj`` and ``cow.obj``,
    :func:`translucency.data.example_path`, take longer) in homogeneous marble:

    >>> import tempfile, trimesh, translucency as tl
    >>> ball = trimesh.creation.icosphere(2, radius=4.0)
    >>> ds = tl.acquire_mesh(ball, tempfile.mkdtemp() + "/ball.zarr", "homogeneous:marble", voxel_mm=1.0,
    ...                      points=4, photons=300, index_matched=True)
    >>> ds.n_points, ds.summary["vertices"]
    (4, 162)
    """
    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    out = as_path("out", out)
    photons, seed = whole_number("photons", photons), whole_number("seed", seed, lo=0)
    sample_seed = whole_number("sample_seed", seed if sample_seed is None else sample_seed, lo=0)
    points, chunk_points = whole_number("points", points), whole_number("chunk_points", chunk_points)
    eta, index_matched = _boundary(eta, index_matched)
    angles, bins = _angle_axes(incidence, azimuths, exit_bins)
    g, scale_mm, voxel_mm = _object_numbers(g, scale_mm, voxel_mm, up, unscattered)
    run = Run("acquire mesh", max_memory=max_memory, reporter=reporter)
    name, volume, path = sample_of(sample)
    mesh_file = mesh_file_of(mesh)
    claim_output(out, "mesh data set", overwrite=overwrite, inputs=[mesh_file, path], reuse=True)
    obj = _object_with_points(mesh, mesh_file, scale_mm, up, points)
    scan = dict(n_points=points, photons=photons, seed=seed, chunk_points=chunk_points,
                index_matched=bool(index_matched), reentry=bool(reentry), unscattered=unscattered,
                incidence=angles, exit_bins=bins)  # fmt: skip
    if name is None:
        volume = volume if path is None else load_volume(path)
        estimate = _mesh_estimate(run, out, obj, scan, volume.sigma_s.size / 3)
    else:  # before the filling is generated
        estimate = _mesh_estimate(run, out, obj, scan, resources.memory.object_voxels(obj.extents, voxel_mm))
        volume = object_volume(name, obj, voxel_mm, g=g, seed=sample_seed)
    volume = _with_eta(volume, eta)
    check_filling(obj, volume)
    state = _timed_mesh(run, out, obj, volume, scan, estimate)
    with run.work("acquire", total=points, fresh=state is None and bytes_at(out) == 0) as work:
        work.update(completed=points - to_acquire(state, points), item="points")
        rest = dict(overwrite=overwrite, progress=_steps(work, progress), scheduler=scheduler)
        scan_mesh(obj, volume, out, inputs=[mesh_file, path], **scan, **rest)
    ds = open_mesh_dataset(out)
    ds.summary = _mesh_summary(run, out, ds, len(obj.vertices), photons, seed)
    return ds


def _boundary(eta, index_matched) -> tuple[float | None, bool]:
    """(η of the boundary or None: the sample's own, whether it is index-matched) of ``eta`` and
    ``index_matched`` (``eta=1``), checked.

    Examples
    --------
    >>> _boundary(None, False), _boundary(1.0, False), _boundary(None, True), _boundary(1.4, False)
    ((None, False), (None, True), (None, True), (1.4, False))
    """
    if eta is None:
        return None, bool(index_matched)
    eta = float(check_option("eta", eta, lo=1.0))
    if index_matched and eta != 1.0:
        raise TranslucencyError(f"eta: index_matched=True is eta=1; give one of them, not eta={eta:g} too")
    return (None, True) if eta == 1.0 else (eta, False)


def _with_eta(volume: Volume, eta: float | None) -> Volume:
    """``volume`` with its boundary's η (None: as it is); its description says so (a resume compares it)."""
    if eta is None or eta == volume.eta:
        return volume
    return dataclasses.replace(volume, eta=eta, description={**volume.description, "eta": eta})


def _object_numbers(g, scale_mm, voxel_mm, up, unscattered):
    """The object's numbers (g; mm per file unit; voxel side, mm) and its options, checked before reading."""
    g = float(check_option("g", g, lo=-1, hi=1, open_lo=True, open_hi=True))
    scale_mm = float(check_option("scale_mm", scale_mm, lo=0, open_lo=True))
    voxel_mm = float(check_option("voxel_mm", voxel_mm, lo=0, open_lo=True))
    if up not in UP_AXES:  # an option: before the mesh is read
        raise TranslucencyError(f"up: expected one of z, y, x, got {up!r}")
    if unscattered not in UNSCATTERED:
        raise TranslucencyError(f"unscattered: expected one of {', '.join(UNSCATTERED)}, got {unscattered!r}")
    return g, scale_mm, voxel_mm


def _object_with_points(mesh, mesh_file, scale_mm: float, up: str, points: int):
    """The object's mesh in mm, refused where it has fewer vertices than incident ``points``."""
    obj = object_of(mesh, mesh_file, scale_mm, up)
    V = len(obj.vertices)
    if points > V:  # before any estimate: the incident points are vertices of the mesh
        raise TranslucencyError(
            f"points: need 1 to {V:,} incident points (the mesh's vertices), got {points:,}"
        )
    return obj


def _mesh_estimate(run: Run, out: Path, obj, scan: dict, voxels):
    """The object scan's memory estimate for ``voxels`` voxels, checked against the run's limit."""
    n = resources.memory.mesh_acquisition(
        vertices=len(obj.vertices),
        faces=len(obj.faces),
        points=scan["n_points"],
        photons=scan["photons"],
        chunk=scan["chunk_points"],
        voxels=voxels,
        directions=scan["incidence"].count,
        exit_bins=0 if scan["exit_bins"] is None else scan["exit_bins"].count,
    )
    return run.check(n, out, resumed=True)  # a resumed acquisition keeps what is there


def _timed_mesh(run: Run, out: Path, obj, volume: Volume, scan: dict, estimate) -> Resumed | None:
    """The object scan's time estimate, its information line and its note for Ctrl-C; the data set it
    resumes, if any."""
    points, photons, V = scan["n_points"], scan["photons"], len(obj.vertices)
    angles, bins = scan["incidence"], scan["exit_bins"]
    same = {
        "volume": json.loads(json.dumps(volume.description)),  # as the header records it
        "n_points": points,
        "photons": photons,
        "seed": scan["seed"],
        "chunk": scan["chunk_points"],
        "vertices": V,
        "reentry": scan["reentry"],
    }
    state = resumable(out, open_mesh_dataset, lambda request: matches(request, same))
    timing = run.time(
        resources.timing.mesh_acquisition_units(
            points=to_acquire(state, points), photons=photons * angles.count, vertices=V
        )
    )
    run.kept = lambda: kept_chunks(out, open_mesh_dataset)
    run.info(
        f"{resuming(state)}{to_acquire(state, points)} incident points x {photons:,} photons x 3 channels"
        f"{f' x {angles.count} directions' if angles.count > 1 else ''}"
        f"{f' ({bins.count} exit bins)' if bins else ''} on a "
        f"mesh of {V:,} vertices, {' x '.join(f'{v:.1f}' for v in obj.extents)} mm; "
        f"time {timing.text()}, memory ~{estimate.memory / 2**20:,.0f} MiB",
    )
    return state


def _mesh_summary(run: Run, out: Path, ds: MeshDataset, V: int, photons: int, seed: int) -> dict:
    """The numbers of ``translucency acquire mesh --json``."""
    return run.summary(
        {
            "command": "acquire mesh",
            "out": out,
            "points": ds.n_points,
            "vertices": V,
            "photons": photons,
            "directions": ds.incidence.count,
            "exit_bins": 0 if ds.exit_bins is None else ds.exit_bins.count,
            "seed": seed,
            "complete": ds.complete(),
            "seconds": run.seconds(),
        }
    )


def _angle_axes(incidence, azimuths, exit_bins) -> tuple[Incidence, ExitBins | None]:
    """The angle axes of an acquisition (``--incidence``, ``--azimuths``, ``--exit-bins``), checked."""
    angles = Incidence(tuple(float(t) for t in incidence), whole_number("azimuths", azimuths))
    return angles, ExitBins(whole_number("exit_bins", exit_bins)) if exit_bins else None


def _steps(work, progress: Callable[[int, int], None] | None) -> Callable[[int, int], None]:
    """The stage's ``progress(done, total)``: the run's progress bar, and the caller's ``progress``."""

    def step(done: int, total: int) -> None:
        work.update(completed=done, item="points")
        if progress is not None:
            progress(done, total)

    return step
