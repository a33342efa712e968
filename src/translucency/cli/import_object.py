"""``translucency import object``: a lab's multi-view HDR photographs of a laser stepped over a scanned
object (with the cameras' calibration) as a mesh data set that ``fit``, ``render``, ``info`` and the report
read as they read ``acquire mesh``'s."""

from __future__ import annotations

from pathlib import Path

import typer

from .._validate import TranslucencyError, check_option
from ..io.outputs import claim_output
from ._common import dataset_overwrite_option, finish, json_option, progress, quiet_option, user_errors


@user_errors
def import_object_cmd(
    rig: Path = typer.Argument(
        ...,
        help="The rig file object.json (or its folder): mesh, cameras, shots (docs/object-rig.md).",
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Output mesh data set (Zarr directory)."),
    exit_law: str = typer.Option(
        None,
        "--exit-law",
        help="Radiance to exitance: lambertian (pi L), dielectric (F_t/(1 - F_dr) of the boundary's eta) "
        "or from-views (a law estimated from vertices two cameras see); default the rig file's.",
    ),
    chunk: int = typer.Option(8, "--chunk", help="Laser shots per chunk (unit of resuming and memory)."),
    overwrite: bool = dataset_overwrite_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Import multi-view photographs of a laser scanned over a real object as a mesh data set."""
    from ..io.mesh_dataset import (
        open_mesh_dataset,
    )  # heavy: Mitsuba, OpenCV and trimesh load only when it runs
    from ..rig.object import import_object, read_object_rig

    check_option("--chunk", chunk, lo=1)
    if exit_law is not None and exit_law not in ("from-views", "dielectric", "lambertian"):
        raise TranslucencyError(f"--exit-law: one of from-views, dielectric, lambertian; got {exit_law!r}")
    setup = read_object_rig(rig)  # a bad rig file: one line before the output is judged
    claim_output(out, "mesh data set", overwrite=overwrite, inputs=setup.files, reuse=True)
    with progress(quiet) as bar:
        task = bar.add_task("import", total=len(setup.shots), item="shots")
        info = import_object(
            setup.path,
            out,
            chunk_points=chunk,
            overwrite=overwrite,
            exit_law=exit_law,
            progress=lambda done, total: bar.update(task, completed=done),
        )
    ds = open_mesh_dataset(out)
    mb = info["bytes_read"] / 2**20
    summary = {
        "command": "import object",
        "out": out,
        "points": ds.n_points,
        "vertices": int(ds.header["n_vertices"]),
        "cameras": info["cameras"],
        "exit_law": info["exit_law"],
        "flags": info["flags"],
        "energy": info["energy"],
        "images_MB": mb,
        "seconds": info["seconds"],
        "throughput_MB_s": mb / max(info["seconds"], 1e-9),
    }
    errors = ", ".join(
        f"{c['name']} {c['reprojection_px'].get('pose', float('nan')):.2f} px" for c in info["cameras"]
    )
    finish(
        as_json,
        quiet,
        summary,
        [
            f"mesh data set: {out} ({ds.n_points} shots x {summary['vertices']:,} vertices; poses {errors}; "
            f"exit law {info['exit_law']['law']}; unseen {info['flags']['unseen']:,} pairs filled)"
        ],
    )
