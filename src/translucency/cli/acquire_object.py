"""``translucency acquire object-photographs``: a virtual object rig — Mitsuba 3 photographs of a filled
mesh lit by a laser at surface points, from calibrated cameras around it — written as a lab would hand
them to ``translucency import object``."""

from __future__ import annotations

from pathlib import Path

import typer

from .._validate import TranslucencyError, check_option
from ..acquire.names import GENERATORS
from ._common import finish, json_option, overwrite_option, progress, quiet_option, user_errors
from ._run import Run

SAMPLES = ", ".join(GENERATORS)


@user_errors
def acquire_object_photographs_cmd(
    out: Path = typer.Option(
        ..., "--out", "-o", help="Output folder: object.json, object.ply, cameras, shots."
    ),
    mesh: Path = typer.Option(None, "--mesh", help="Mesh file (OBJ/PLY/STL); default the built-in pig."),
    scale: float = typer.Option(1.0, "--scale", help="Millimetres per mesh-file unit."),
    up: str = typer.Option("z", "--up", help="The mesh file's up axis (z, y or x), turned to +z."),
    material: str = typer.Option("marble", "--material", "-m", help=f"Filling: {SAMPLES}."),
    voxel: float = typer.Option(0.5, "--voxel", help="Voxel size of the filling, mm."),
    points: int = typer.Option(
        8, "--points", help="Laser positions (farthest-point sample of the vertices)."
    ),
    cameras: int = typer.Option(6, "--cameras", help="Cameras on a sphere around the object."),
    resolution: tuple[int, int] = typer.Option(
        (128, 128), "--resolution", help="Image width and height, pixels."
    ),
    spp: int = typer.Option(64, "--spp", help="Samples per pixel of each of the two repeated frames."),
    beam: float = typer.Option(0.3, "--beam", help="Radius of the laser's spot on the surface, mm."),
    checkerboards: bool = typer.Option(
        False, "--checkerboards", help="Give intrinsics as checkerboard photographs (OpenCV calibrates)."
    ),
    seed: int = typer.Option(0, "--seed", help="Random seed of the filling, the renders and the sensor."),
    image_format: str = typer.Option("pfm", "--format", help="pfm or exr."),
    overwrite: bool = overwrite_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Photograph a virtual object with Mitsuba 3 (a laser spot per point, N calibrated cameras, sensor noise,
    dark offset, vignetting, a saturated spot, drifting power): a lab's hand-over for `import object`."""
    from ..acquire.mesh import (
        check_filling,
        object_volume,
    )  # heavy: Mitsuba and trimesh load only when it runs
    from ..acquire.objects import make_pig
    from ..io.mesh import check_mesh_file, load_mesh
    from ..rig.object.photographs import LaserBeam, photograph_object

    check_option("--points", points, lo=1)
    check_option("--cameras", cameras, lo=1, hi=64)
    check_option("--spp", spp, lo=1)
    check_option("--beam", beam, lo=0, open_lo=True)
    check_option("--voxel", voxel, lo=0, open_lo=True)
    check_option("--scale", scale, lo=0, open_lo=True)
    for v in resolution:
        check_option("--resolution", v, lo=8, hi=8192)
    if up not in ("z", "y", "x"):
        raise TranslucencyError(f"--up: expected one of z, y, x, got {up!r}")
    if image_format not in ("pfm", "exr"):
        raise TranslucencyError(f"--format: pfm or exr, got {image_format!r}")
    if mesh is not None:
        check_mesh_file(mesh, "--mesh")
    run = Run("acquire object-photographs", max_memory=None, quiet=quiet)
    run.claim_folder(out, overwrite=overwrite, inputs=[mesh])
    obj = load_mesh(mesh, scale_mm=scale, up=up) if mesh is not None else make_pig()
    if points > len(obj.vertices):
        raise TranslucencyError(f"--points: need 1 to {len(obj.vertices):,} laser positions, got {points:,}")
    vol = object_volume(material, obj, voxel, seed=seed)
    check_filling(obj, vol)
    run.info(
        f"{points} laser positions x {cameras} cameras x 3 channels x 2 frames at {spp} spp "
        f"({resolution[0]} x {resolution[1]} px), mesh of {len(obj.vertices):,} vertices"
    )
    with progress(quiet) as bar:
        task = bar.add_task("photograph", total=points, item="shots")
        res = photograph_object(
            obj,
            vol,
            out,
            n_points=points,
            n_cameras=cameras,
            resolution=resolution,
            spp=spp,
            seed=seed,
            beam=LaserBeam(radius_mm=beam),
            image_format=image_format,
            checkerboards=checkerboards,
            spot_radius_mm=max(0.5, 2 * beam),
            progress=lambda done, total: bar.update(task, completed=done),
        )
    run.created.clear()  # done: the photographs stay
    summary = {
        "command": "acquire object-photographs",
        "out": out,
        "points": points,
        "cameras": cameras,
        "incident": res["incident"],
        "seconds": res["seconds"],
    }
    finish(
        as_json,
        quiet,
        summary,
        [f"photographs: {out / 'object.json'} (import with `translucency import object`)"],
    )
