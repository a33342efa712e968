"""``translucency render``: a fitted object relit — irradiance per vertex, the sparse transport, a picture
through Mitsuba (EXR + PNG), and with ``--reference`` the path-traced reference and their comparison."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import typer
from rich.table import Table

from .. import resources
from .._validate import TranslucencyError, check_option
from ..io.inputs import expect_input
from ..io.model_file import load_model, read_header
from ..io.outputs import claim_folder
from ..render import MAX_PAIRS, default_radius
from ..render.camera import Camera
from ..render.figure import figure2
from ..render.lights import parse_light
from ..render.object import boundary_eta, object_of_model, volume_of_dataset
from ._common import json_option, max_memory_option, overwrite_option, quiet_option, user_errors
from ._run import Run


@user_errors
def render(
    model: Path = typer.Argument(..., help="A per-vertex model file (translucency fit on a mesh data set)."),
    out: Path = typer.Option(
        Path("render"), "--out", "-o", help="Directory for ours.exr/.png (and the reference)."
    ),
    light: list[str] = typer.Option(
        None,
        "--light",
        help="point:x,y,z[,I] | directional:dx,dy,dz[,E] | spot:x,y,z,tx,ty,tz,cutoff_deg[,I] | env:L | "
        "env:MAP.exr[,scale] (mm, W/sr, W/mm^2, W/(mm^2 sr)).",
    ),
    view: str = typer.Option(
        "1,-1.6,0.7", "--view", help="Camera direction from the object's centre, x,y,z."
    ),
    size: tuple[int, int] = typer.Option((320, 240), "--size", help="Image width and height in pixels."),
    reference: bool = typer.Option(
        False, "--reference", help="Also path-trace the reference (Mitsuba volpath) and compare."
    ),
    spp: int = typer.Option(32, "--spp", help="Samples per pixel of each of the two reference renders."),
    radius: float = typer.Option(
        None,
        "--radius",
        help="Near radius of the transport, mm: pairs within it summed exactly, those beyond it through the "
        "hierarchical far field (default: the 99% energy radius, or less where the pairs would not fit).",
    ),
    overwrite: bool = overwrite_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Relight a fitted object: irradiance per vertex, sparse transport, a picture through Mitsuba (EXR + PNG)."""  # noqa: E501 — Typer lists the docstring verbatim as the command's one-line help; a line break would show in `translucency --help`
    check_option("--spp", spp, lo=1)
    check_option("--radius", radius, lo=1e-6, hi=1e9)  # 1 nm to 1000 km (the far field divides by r²)
    for value in size:
        check_option("--size", value, lo=1, hi=16384)
    run = Run("render", max_memory=max_memory, quiet=quiet)

    expect_input(model, ("model file",))  # a data set or a mesh file where the model belongs: say so
    m = load_model(model)
    header = read_header(model)
    if m.geometry != "mesh":
        raise TranslucencyError(
            f"{model}: a planar model; render needs a per-vertex model of a mesh data set"
        )
    mesh, dheader = object_of_model(m, header)
    try:
        direction = [float(v) for v in view.split(",")]
    except ValueError:
        direction = []
    if len(direction) != 3 or not np.isfinite(direction).all() or not np.abs(direction).max() > 0:
        raise TranslucencyError(f"--view: expected three finite numbers x,y,z not all zero, got {view!r}")
    direction = np.asarray(direction) / np.abs(direction).max()  # 1e308 or 1e-320: no overflow, no 0
    direction /= np.linalg.norm(direction)
    lights = [parse_light(t) for t in (light or ["point:60,-80,120,2e4"])]
    if len(lights) > 1:
        raise TranslucencyError("--light: one light per render for now (run once per light)")
    V = len(mesh.vertices)
    rad = default_radius(m, mesh) if radius is None else float(radius)  # the transport's, for the estimates
    picture = dict(
        vertices=V,
        surface_mm2=float(mesh.area),
        radius_mm=rad,
        width=size[0],
        height=size[1],
        reference=reference,
        spp_reference=spp,
        max_pairs=MAX_PAIRS,
    )
    run.check(resources.memory.rendering(**picture), out)
    claim_folder(out, overwrite=overwrite, inputs=[model, header.get("meta", {}).get("dataset") or None])
    timing = run.time(resources.timing.rendering_units(**picture))
    run.info(f"render of {V:,} vertices at {size[0]} x {size[1]}; time {timing.text()}")
    run.start()  # the camera and the reference's volume are part of the work
    cam = Camera.looking_at(mesh, direction, *size)
    if abs(direction[2]) > 0.999:  # looking straight up or down: the image's up is +y, not +z
        cam = dataclasses.replace(cam, up=(0.0, 1.0, 0.0))
    vol = volume_of_dataset(mesh, dheader) if reference else None
    steps = 4 if reference else 3
    with run.work("render", total=steps) as work:
        res = figure2(
            m,
            mesh,
            lights[0],
            out,
            volume=vol,
            camera=cam,
            spp_reference=spp,
            radius=radius,
            eta=boundary_eta(dheader),
            progress=lambda done, total, name: work.update(completed=done, total=total, item=name),
        )
        work.update(completed=steps, item="done")
        work.fresh = not res.get("reference_cached", False)
    table = Table(title=f"render of {model.name}", show_header=False)
    for k, v in res.items():
        table.add_row(k, f"{v:.4g}" if isinstance(v, float) else str(v))
    summary = {"command": "render", "model": model, "images": out, **res, "light": _light_record(lights[0])}
    run.finish(as_json, summary, [table, f"images: {out}"])


def _light_record(light) -> dict:
    """A light as JSON: its kind (point, directional, spot, environment) and its parameters."""
    return {"kind": type(light).__name__.removesuffix("Light").lower(), **dataclasses.asdict(light)}
