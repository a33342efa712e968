"""``translucency acquire planar|mesh|photographs``: measurements simulated by photon transport (virtual
DISCO: a planar sample, a 3D object) and a virtual rig's photographs for ``translucency import images``."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import NamedTuple

import numpy as np
import typer

from .. import resources
from .._validate import TranslucencyError, check_option
from ..acquire.names import GENERATORS
from ..io.dataset import open_dataset
from ..io.inputs import expect_input
from ..io.mesh_dataset import open_mesh_dataset
from ..io.outputs import claim_folder, claim_output
from ._common import (
    console,
    dataset_overwrite_option,
    err_console,
    json_option,
    max_memory_option,
    quiet_option,
    scheduler_option,
    user_errors,
)
from ._run import Run, bytes_at, kept_chunks

#: the sample generators, as --help lists them (the one list make_sample refuses others with)
SAMPLES = ", ".join(GENERATORS) + " (<name>: one of `translucency materials`)"

app = typer.Typer(
    help="Virtual DISCO: simulate measurements by photon transport (Mitsuba 3 / Dr.Jit).",
    no_args_is_help=True,
)


@app.command("photographs")
@user_errors
def acquire_photographs_cmd(
    out: Path = typer.Option(
        ..., "--out", "-o", help="Output folder: images, positions.csv, calibration.json."
    ),
    material: str = typer.Option(
        None,
        "--material",
        "-m",
        help=f"Sample generator: {SAMPLES}.",
    ),
    volume: Path = typer.Option(None, "--volume", help="A user's volume (.npz, as acquire planar)."),
    grid: int = typer.Option(2, "--grid", help="Incident points per axis (grid x grid)."),
    span: float = typer.Option(4.0, "--span", help="Side of the incident grid, mm (centred on the sample)."),
    size: tuple[float, float, float] = typer.Option(
        (12.0, 12.0, 4.0), "--size", help="Generated slab: width height thickness, mm."
    ),
    voxel: float = typer.Option(0.5, "--voxel", help="Voxel size of generated samples, mm."),
    camera: tuple[float, float, float] = typer.Option(
        (0.0, -8.0, 11.0), "--camera", help="Camera position relative to the sample's centre, mm."
    ),
    fov: float = typer.Option(40.0, "--fov", help="Horizontal field of view, degrees."),
    resolution: tuple[int, int] = typer.Option(
        (64, 64), "--resolution", help="Image width and height, pixels."
    ),
    spp: int = typer.Option(64, "--spp", help="Samples per pixel of Mitsuba's volpath."),
    seed: int = typer.Option(0, "--seed", help="Random seed of the sample, renders and sensor noise."),
    image_format: str = typer.Option("pfm", "--format", help="pfm or exr."),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Replace an earlier output folder of translucency (never anything else)."
    ),
):
    """Photograph a virtual sample with Mitsuba 3 (narrow beam per point, oblique perspective camera,
    sensor noise, dark offset, vignetting, saturation): a lab's hand-over for `translucency import images`."""
    from ..acquire import PlanarSetup, load_volume, make_sample  # heavy: Mitsuba loads only when it runs
    from ..rig.planar.photographs import VirtualCamera, photograph_sample

    check_option("--grid", grid, lo=1, hi=64)
    check_option("--spp", spp, lo=1)
    check_option("--fov", fov, lo=1, hi=120)
    for v in resolution:
        check_option("--resolution", v, lo=8, hi=8192)
    if (material is None) == (volume is None):
        raise TranslucencyError("give exactly one of --material NAME or --volume FILE.npz")
    expect_input(volume, ("volume file",), "--volume")
    claim_folder(out, overwrite=overwrite, inputs=[volume])
    vol = load_volume(volume) if volume is not None else make_sample(material, size, voxel, seed=seed)
    W, H, _ = vol.size_mm
    setup = PlanarSetup(grid=(grid, grid), span=(span, span), pitch=0.25, window=min(W, H) / 2)
    setup.check(vol)
    x_i = setup.incident_points(vol)
    centre = np.array([W / 2, H / 2, 0.0])
    cam = VirtualCamera(tuple(centre + np.asarray(camera)), tuple(centre), fov, *resolution)
    err_console.print(
        f"{len(x_i)} photographs x 3 channels at {spp} spp ({resolution[0]} x {resolution[1]} px)"
    )
    res = photograph_sample(vol, x_i, out, camera=cam, spp=spp, seed=seed, image_format=image_format)
    console.print(
        f"photographs: {out} (markers fit to {res['rms_px']:.3f} px rms; true homography "
        f"{np.round(res['homography'].matrix, 4).tolist()})"
    )


@app.command("planar")
@user_errors
def acquire_planar_cmd(
    out: Path = typer.Option(..., "--out", "-o", help="Output data set (Zarr directory)."),
    material: str = typer.Option(
        None,
        "--material",
        "-m",
        help=f"Sample generator: {SAMPLES}.",
    ),
    volume: Path = typer.Option(
        None, "--volume", help="A user's volume: .npz with sigma_s, sigma_a (Z,Y,X,3) in 1/mm, voxel_mm."
    ),
    photons: int = typer.Option(10_000, "--photons", "-N", help="Photons per incident point and channel."),
    seed: int = typer.Option(
        0, "--seed", help="Random seed of the photons (results are deterministic for a seed)."
    ),
    sample_seed: int = typer.Option(
        None,
        "--sample-seed",
        help="Seed of the generated sample (default: --seed). A held-out truth of the same sample: "
        "the same --sample-seed, another --seed.",
    ),
    grid: int = typer.Option(8, "--grid", help="Incident points per axis (grid x grid)."),
    span: float = typer.Option(8.0, "--span", help="Side of the incident grid, mm (centred on the sample)."),
    pitch: float = typer.Option(0.25, "--pitch", help="Pixel size, mm."),
    window: float = typer.Option(8.0, "--window", help="Window side around each incident point, mm."),
    size: tuple[float, float, float] = typer.Option(
        (20.0, 20.0, 8.0), "--size", help="Generated slab: width height thickness, mm."
    ),
    voxel: float = typer.Option(0.25, "--voxel", help="Voxel size of generated samples, mm."),
    g: float = typer.Option(0.0, "--g", help="Henyey-Greenstein anisotropy of generated samples."),
    angle: float = typer.Option(0.0, "--angle", help="Angle of incidence from the normal, degrees."),
    index_matched: bool = typer.Option(
        False, "--index-matched", help="No Fresnel reflection at the boundary."
    ),
    chunk: int = typer.Option(16, "--chunk", help="Incident points per chunk (unit of resuming)."),
    dtype: str = typer.Option("float32", "--dtype", help="Storage of R_d and variance: float32 or float16."),
    overwrite: bool = dataset_overwrite_option(),
    scheduler: str = scheduler_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Scan a pencil beam over a planar sample and record R_d around each incident point."""
    from ..acquire import (  # heavy: Mitsuba, Dask and SciPy load only when an acquisition runs
        PlanarSetup,
        acquire_planar,
        estimate_seconds,
        load_volume,
        make_sample,
        probe_walk,
    )
    from ..cluster import parse_scheduler

    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    check_option("--photons", photons, lo=1)
    check_option("--seed", seed, lo=0)
    check_option("--sample-seed", sample_seed, lo=0)
    check_option("--grid", grid, lo=1, hi=4096)
    check_option("--chunk", chunk, lo=1)
    check_option("--g", g, lo=-1, hi=1, open_lo=True, open_hi=True)
    for name, value in (("--span", span), ("--pitch", pitch), ("--window", window), ("--voxel", voxel)):
        check_option(name, value, lo=0, open_lo=True)
    for value in size:
        check_option("--size", value, lo=0, open_lo=True, hi=1e5)
    check_option("--voxel", voxel, hi=min(size))  # at least one voxel across the thinnest side
    check_option("--pitch", pitch, hi=window)  # at least one pixel a window

    check_option("--angle", angle, lo=0, hi=90, open_hi=True)
    run = Run("acquire planar", max_memory=max_memory, quiet=quiet)
    if (material is None) == (volume is None):
        raise TranslucencyError("give exactly one of --material NAME or --volume FILE.npz")
    expect_input(volume, ("volume file",), "--volume")
    if dtype not in ("float32", "float16"):
        raise TranslucencyError(f"--dtype: expected float32 or float16, got {dtype!r}")

    def need(voxels):
        n = resources.memory.planar_acquisition(
            grid=grid, pitch=pitch, window=window, photons=photons, chunk=chunk, voxels=voxels, dtype=dtype
        )
        return run.check(n, out, resumed=True)  # a resumed acquisition keeps what is there

    if volume is None:  # before the sample is generated
        estimate = need(resources.memory.slab_voxels(size, voxel))
    claim_output(out, "planar data set", overwrite=overwrite, inputs=[volume], reuse=True)
    sample_seed = seed if sample_seed is None else sample_seed
    vol = (
        load_volume(volume)
        if volume is not None
        else make_sample(material, size, voxel, g=g, seed=sample_seed)
    )
    if volume is not None:
        estimate = need(vol.sigma_s.size / 3)
    setup = PlanarSetup(
        grid=(grid, grid),
        span=(span, span),
        pitch=pitch,
        window=window,
        photons=photons,
        seed=seed,
        theta_inc_deg=angle,
        index_matched=index_matched,
        chunk_points=chunk,
        dtype=dtype,
    )
    setup.check(vol)
    walk = probe_walk(vol, setup)  # a short trace of this volume: its steps per photon, this machine's speed
    P = grid * grid
    state = _resumable(out, open_dataset, lambda request: request.get("setup") == _jsonable(setup))
    share = 1.0 if state is None else state.points_left / P  # what is left of the work
    units = resources.timing.planar_acquisition_units(
        points=round(share * P),
        photon_steps=share * estimate_seconds(vol, setup, steps_per_second=1.0, probe=walk),
        pixels=round(share * P) * setup.window_pixels() ** 2,
    )
    first = resources.timing.probe_factor("acquire planar", "photon_steps", walk.seconds_per_step)
    timing = run.time(units, (first, "from a probe of the walk on this sample"))
    run.kept = lambda: kept_chunks(out, open_dataset)
    run.info(
        f"{_resuming(state)}{round(share * P)} incident points x {photons:,} photons x 3 channels on a "
        f"{' x '.join(f'{v:g}' for v in vol.size_mm)} mm slab; time {timing.text()}, "
        f"memory ~{estimate.memory / 2**20:,.0f} MiB",
    )
    with run.work("acquire", total=P, fresh=state is None and bytes_at(out) == 0) as work:
        work.update(completed=P - round(share * P), item="points")
        acquire_planar(
            vol,
            setup,
            out,
            overwrite=overwrite,
            inputs=[volume],
            progress=lambda done, total: work.update(completed=done, item="points"),
            scheduler=scheduler,
        )
    ds = open_dataset(out)
    summary = {
        "command": "acquire planar",
        "out": out,
        "points": ds.n_points,
        "window_pixels": ds.window,
        "photons": photons,
        "seed": seed,
        "complete": ds.complete(),
        "seconds": run.seconds(),
    }
    run.finish(as_json, summary, [f"data set: {out}"])


@app.command("mesh")
@user_errors
def acquire_mesh_cmd(
    out: Path = typer.Option(..., "--out", "-o", help="Output mesh data set (Zarr directory)."),
    mesh: Path = typer.Option(
        None, "--mesh", help="A closed mesh (OBJ/PLY/STL); default: the procedural pig."
    ),
    scale: float = typer.Option(1.0, "--scale", help="Millimetres per mesh unit."),
    material: str = typer.Option(
        None,
        "--material",
        "-m",
        help=f"Filling (in object space): {SAMPLES}; default marble.",
    ),
    volume: Path = typer.Option(
        None,
        "--volume",
        help="A user's filling: .npz with sigma_s, sigma_a (Z,Y,X,3) in 1/mm, voxel_mm, over the mesh's "
        "bounding box (z index 0 at the top).",
    ),
    up: str = typer.Option("z", "--up", help="The mesh file's up axis (z, y or x), turned to +z."),
    voxel: float = typer.Option(0.5, "--voxel", help="Voxel size of the filling, mm."),
    points: int = typer.Option(
        64, "--points", help="Incident points (farthest-point sample of the vertices)."
    ),
    photons: int = typer.Option(20_000, "--photons", "-N", help="Photons per incident point and channel."),
    seed: int = typer.Option(0, "--seed", help="Random seed."),
    g: float = typer.Option(0.0, "--g", help="Henyey-Greenstein anisotropy."),
    chunk: int = typer.Option(8, "--chunk", help="Incident points per chunk (unit of resuming)."),
    index_matched: bool = typer.Option(
        False, "--index-matched", help="No Fresnel reflection at the surface."
    ),
    overwrite: bool = dataset_overwrite_option(),
    scheduler: str = scheduler_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Pencil beams at surface points of a 3D object; exits tallied per vertex (R_d in mm^-2)."""
    from ..acquire import load_volume  # heavy: Mitsuba, Dask, trimesh and scikit-image load only when it runs
    from ..acquire.mesh import acquire_mesh, check_filling, object_volume
    from ..acquire.objects import make_pig
    from ..cluster import parse_scheduler
    from ..io.mesh import check_mesh_file, load_mesh

    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    check_option("--photons", photons, lo=1)
    check_option("--seed", seed, lo=0)
    check_option("--points", points, lo=1)
    check_option("--chunk", chunk, lo=1)
    check_option("--g", g, lo=-1, hi=1, open_lo=True, open_hi=True)
    check_option("--scale", scale, lo=0, open_lo=True)
    check_option("--voxel", voxel, lo=0, open_lo=True)

    if up not in ("z", "y", "x"):  # an option: before the mesh is read
        raise TranslucencyError(f"--up: expected one of z, y, x, got {up!r}")
    run = Run("acquire mesh", max_memory=max_memory, quiet=quiet)
    if material is not None and volume is not None:
        raise TranslucencyError("give one of --material NAME or --volume FILE.npz, not both")
    expect_input(volume, ("volume file",), "--volume")
    expect_input(mesh, ("mesh file",), "--mesh")
    if mesh is not None:
        check_mesh_file(mesh, "--mesh")  # a folder or a missing file: named before the output is judged
    claim_output(out, "mesh data set", overwrite=overwrite, inputs=[mesh, volume], reuse=True)
    obj = load_mesh(mesh, scale_mm=scale, up=up) if mesh is not None else make_pig()
    V = len(obj.vertices)
    if points > V:  # before any estimate: the incident points are vertices of the mesh
        raise TranslucencyError(
            f"--points: need 1 to {V:,} incident points (the mesh's vertices), got {points:,}"
        )

    def need(voxels):
        n = resources.memory.mesh_acquisition(
            vertices=V, faces=len(obj.faces), points=points, photons=photons, chunk=chunk, voxels=voxels
        )
        return run.check(n, out, resumed=True)  # a resumed acquisition keeps what is there

    if volume is not None:
        vol = load_volume(volume)
        estimate = need(vol.sigma_s.size / 3)
    else:  # before the filling is generated
        estimate = need(resources.memory.object_voxels(obj.extents, voxel))
        vol = object_volume(material or "marble", obj, voxel, g=g, seed=seed)
    check_filling(obj, vol)
    same = {"n_points": points, "photons": photons, "seed": seed, "chunk": chunk, "vertices": V}
    state = _resumable(out, open_mesh_dataset, lambda request: _matches(request, same))
    left = points if state is None else state.points_left
    units = resources.timing.mesh_acquisition_units(points=left, photons=photons, vertices=V)
    timing = run.time(units)
    run.kept = lambda: kept_chunks(out, open_mesh_dataset)
    run.info(
        f"{_resuming(state)}{left} incident points x {photons:,} photons x 3 channels on a mesh of "
        f"{V:,} vertices, {' x '.join(f'{v:.1f}' for v in obj.extents)} mm; "
        f"time {timing.text()}, memory ~{estimate.memory / 2**20:,.0f} MiB",
    )
    with run.work("acquire", total=points, fresh=state is None and bytes_at(out) == 0) as work:
        work.update(completed=points - left, item="points")
        acquire_mesh(
            obj,
            vol,
            out,
            n_points=points,
            photons=photons,
            seed=seed,
            chunk_points=chunk,
            index_matched=index_matched,
            overwrite=overwrite,
            inputs=[mesh, volume],
            progress=lambda done, total: work.update(completed=done, item="points"),
            scheduler=scheduler,
        )
    ds = open_mesh_dataset(out)
    summary = {
        "command": "acquire mesh",
        "out": out,
        "points": ds.n_points,
        "vertices": len(obj.vertices),
        "photons": photons,
        "seed": seed,
        "complete": ds.complete(),
        "seconds": run.seconds(),
    }
    run.finish(as_json, summary, [f"mesh data set: {out}"])


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
