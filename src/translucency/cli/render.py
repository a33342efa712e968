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
from ..io.model_file import load_model, read_header
from ..render import MAX_PAIRS, default_radius
from ..render.camera import Camera
from ..render.figure import figure2
from ..render.lights import parse_light
from ..render.object import boundary_eta, check_light_outside, object_of_model, volume_of_dataset
from ..render.reference import check_reference
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
        "hierarchical far field (default: the 99% energy radius, or less where the pairs would not fit in a "
        "quarter of --max-memory or of the machine's memory). A smaller radius lowers the memory.",
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
    # the options first (no file read), then the model and what it implies, then the output, then work
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

    m = load_model(model)
    header = read_header(model)
    if m.geometry != "mesh":
        raise TranslucencyError(
            f"{model}: a planar model; render needs a per-vertex model of a mesh data set"
        )
    mesh, dheader = object_of_model(m, header)
    check_light_outside(mesh, lights[0])
    if reference:  # a light volpath cannot render, a filling gone or changed: one line, before any work
        check_reference(lights[0], boundary_eta(dheader))
    vol = volume_of_dataset(mesh, dheader) if reference else None
    V = len(mesh.vertices)
    # the default radius: the model's 99 % energy radius, at most what a share of the memory holds
    budget = resources.memory.transport_budget(run.limit)
    rad = default_radius(m, mesh, max_pairs=min(MAX_PAIRS, 2 * budget)) if radius is None else float(radius)
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
    need = run.check(resources.memory.rendering(**picture), out)
    run.claim_folder(out, overwrite=overwrite, inputs=[model, header.get("meta", {}).get("dataset") or None])
    timing = run.time(resources.timing.rendering_units(**picture))
    what, _, flags = need.what.partition(": ")  # "the transport: --radius"
    run.info(
        f"render of {V:,} vertices at {size[0]} x {size[1]}, transport radius {rad:.3g} mm; time "
        f"{timing.text()}, memory ~{need.memory / 2**30:.2g} GiB (mostly {what}"
        f"{f'; a smaller {flags} lowers it' if flags else ''})"
    )
    cam = Camera.looking_at(mesh, direction, *size)
    if abs(direction[2]) > 0.999:  # looking straight up or down: the image's up is +y, not +z
        cam = dataclasses.replace(cam, up=(0.0, 1.0, 0.0))
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
            radius=rad,
            eta=boundary_eta(dheader),
            progress=lambda done, total, name: work.update(completed=done, total=total, item=name),
        )
        work.update(completed=steps, item="done")
        work.fresh = not res.get("reference_cached", False)
    table = Table(title=f"render of {model.name}", show_header=False)
    for k, v in res.items():
        table.add_row(k, f"{v:.4g}" if isinstance(v, float) else str(v))
    run.finish(
        as_json, {"command": "render", "model": model, "images": out, **res}, [table, f"images: {out}"]
    )
