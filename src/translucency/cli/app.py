"""The ``translucency`` command (Typer + Rich).

Every subcommand has ``--help``.  A user's mistake (bad file, bad parameter)
prints one line starting with ``error:`` and exits with status 2 — never a
traceback.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import json
import math
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from .. import _resources as resources
from .._validate import TranslucencyError, check_option
from .._version import __version__
from ..acquire import PlanarSetup, acquire_planar, estimate_seconds, load_volume, make_sample, probe_walk
from ..acquire.mesh import acquire_mesh, object_volume
from ..acquire.objects import make_pig
from ..cluster import parse_scheduler
from ..evaluate.report import model_label, write_report
from ..fit import check_fit_options, fit_mesh, fit_planar
from ..fit.planar import default_chunk_points
from ..io.dataset import dataset_identity, describe, open_dataset
from ..io.mesh import load_mesh
from ..io.mesh_dataset import describe_mesh, is_mesh_dataset, open_mesh_dataset
from ..io.model_file import ModelFileError, load_model, read_header, save_model
from ..io.outputs import claim_folder, claim_output
from ..model import MATERIALS, check_physics, dipole_total_reflectance
from ..pipeline import DEMO_FITS, run_demo
from ..render.camera import Camera
from ..render.figure import figure2
from ..render.lights import parse_light
from ..render.object import boundary_eta, object_of_model, volume_of_dataset
from ._flags import cli_words
from ._options import scheduler_option as _scheduler_option
from .rig import acquire_photographs_cmd, import_app


class _OneLineErrors(typer.core.TyperGroup):
    """The top command: a usage error (unknown option, a value of the wrong type) is one ``error:`` line
    naming the option, exit status 2, like every other error — not Click's usage box."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except typer._click.exceptions.ClickException as exc:
            if type(exc).__name__ == "NoArgsIsHelpError":  # the help text is the answer
                exc.show()
            else:
                text = " ".join(exc.format_message().split())
                err_console.print(f"[bold red]error:[/] {text}", highlight=False, soft_wrap=True, markup=True)
            sys.exit(exc.exit_code)
        except typer.Abort:
            err_console.print("aborted", highlight=False)
            sys.exit(1)
        sys.exit(rv if isinstance(rv, int) else 0)


app = typer.Typer(
    cls=_OneLineErrors,
    help="Measure, fit, evaluate and render heterogeneous translucent materials "
    "(empirical sum-of-exponentials model of Fuchs et al.). Units: mm, R_d in mm^-2.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console()
err_console = Console(stderr=True)


def _version(value: bool) -> None:
    if value:
        console.print(f"translucency {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """Measure, fit, evaluate and render heterogeneous translucent materials."""


def user_errors(func):
    """Turn a :class:`TranslucencyError` into one ``error:`` line and exit status 2; a warning is one
    ``warning:`` line on stderr."""

    def one_line(message, category, *args, **kwargs):
        text = cli_words(" ".join(str(message).split()))
        err_console.print(f"[yellow]warning:[/] {text}", highlight=False, soft_wrap=True)

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            with warnings.catch_warnings():
                warnings.showwarning = one_line
                return func(*args, **kwargs)
        except TranslucencyError as exc:
            err_console.print(f"[bold red]error:[/] {cli_words(str(exc))}", highlight=False, soft_wrap=True)
            raise typer.Exit(2) from None

    return wrapper


def progress(quiet: bool = False) -> Progress:
    """A Rich progress bar on stderr (none with ``quiet``)."""
    return Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TextColumn("{task.fields[item]}"),
        TimeElapsedColumn(),
        TextColumn("left"),
        TimeRemainingColumn(),  # from the measured rate of the steps done so far
        console=err_console,
        transient=False,
        disable=quiet,
    )


def _max_memory_option():
    return typer.Option(
        None,
        "--max-memory",
        metavar="SIZE",
        help="Most memory the command may use, e.g. 4G or 512M (default: the machine's available memory); "
        "a larger estimate is refused before any work.",
    )


def _quiet_option():
    return typer.Option(
        False, "--quiet", "-q", help="No progress and no information lines; errors still shown."
    )


def _json_option():
    return typer.Option(False, "--json", help="Print a summary as one JSON object on stdout (for scripts).")


def _timed(command: str, units: dict) -> resources.TimeEstimate:
    """The calibrated time estimate of a command (``_resources.estimate_time``)."""
    return resources.estimate_time(command, units)


def _calibrate(command: str, units: dict, seconds: float, fresh: bool = True) -> None:
    """Teach this machine's time calibration how long the work took (not after a resumed run)."""
    if fresh:
        resources.record_time(command, units, seconds)


def _limit(text) -> int | None:
    return None if text is None else resources.parse_size("--max-memory", text)


def _info(quiet: bool, text: str) -> None:
    """An information line on stderr, unless ``quiet``."""
    if not quiet:
        err_console.print(text, highlight=False)


def _jsonable(value):
    """``value`` with every NaN or infinity as null (strict JSON), tuples and paths as lists and strings."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, Path):
        return str(value)
    return value


def _finish(as_json: bool, quiet: bool, summary: dict, lines=()) -> None:
    """The end of a working command: one JSON object on stdout (``--json``), or its result lines."""
    if as_json:
        print(json.dumps(_jsonable(summary), allow_nan=False))
    elif not quiet:
        for line in lines:
            console.print(line)


def _bytes_at(path: Path) -> int:
    """Bytes already at an output path (what a resumed or replaced output frees or keeps)."""
    if path.is_file():
        return path.stat().st_size
    if path.is_dir():
        return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())
    return 0


@app.command()
@user_errors
def demo(
    out: Path = typer.Option(Path("results"), "--out", "-o", help="Directory for the figures and files."),
    terms: int = typer.Option(3, "--terms", "-n", min=1, max=8, help="Exponential terms n of the fits."),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Replace an earlier output of translucency at --out (never anything else)."
    ),
):
    """The main job on the embedded default data: baselines per material, then planar fits
    (iso, aniso, dipole, Burley) with alpha and the Figure 1 report."""

    with progress() as bar:
        task = bar.add_task("demo", total=len(MATERIALS) + len(DEMO_FITS) + 3, item="")

        def step(name):
            bar.update(task, advance=1, item=name)

        outputs = run_demo(out, n_terms=terms, step=step, overwrite=overwrite)
    for what, path in outputs.items():
        console.print(f"{what:>8}: {path}")


@app.command()
@user_errors
def materials(
    eta: float = typer.Option(1.3, help="Relative index of refraction for the dipole's total reflectance."),
):
    """Print Jensen et al. 2001's measured coefficients (mm^-1) and the dipole's R_d."""
    check_option("--eta", eta, lo=0, open_lo=True)

    table = Table(title=f"Jensen et al. 2001 measured materials (eta = {eta})")
    for col in ("name", "sigma_s' R G B [1/mm]", "sigma_a R G B [1/mm]", "R_d dipole", "R_d published"):
        table.add_column(col)
    fmt = lambda a: " ".join(f"{v:.4g}" for v in a)  # noqa: E731
    for name, m in MATERIALS.items():
        rd = dipole_total_reflectance(m.sigma_a, m.sigma_s_prime, eta)
        table.add_row(name, fmt(m.sigma_s_prime), fmt(m.sigma_a), fmt(rd.round(3)), fmt(m.R_d_published))
    console.print(table)


@app.command()
@user_errors
def info(
    path: Path = typer.Argument(..., help="A model file (.model.zip) or a data set (.zarr directory)."),
    as_json: bool = typer.Option(False, "--json", help="Print the fields as one JSON object (for scripts)."),
):
    """Describe a model file or a data set: what it holds, its size on disk, whether it is valid."""
    if path.is_dir():
        ds = open_mesh_dataset(path) if is_mesh_dataset(path) else open_dataset(path)
        _show(path, describe_mesh(ds) if is_mesh_dataset(path) else describe(ds), as_json)
        return
    fields, ok = _info_model(path)
    _show(path, fields, as_json)
    if not ok:
        raise typer.Exit(1)


def _show(path: Path, fields: dict, as_json: bool) -> None:
    """The fields of ``info`` as a table, or as one JSON object on stdout."""
    if as_json:
        print(json.dumps({"path": str(path), **fields}, default=str, indent=2))  # plain: no wrapping
        return
    table = Table(title=str(path), show_header=False)
    for key, value in fields.items():
        table.add_row(f"[bold]{key}[/]", str(value), style="red" if str(value).startswith("no") else None)
    console.print(table)


def _info_model(path: Path) -> tuple[dict, bool]:
    """``info``'s fields of a model file, and whether it is valid (intact and physical)."""
    size = path.stat().st_size if path.exists() else 0
    header = read_header(path)  # a ModelFileError is a TranslucencyError: one line, exit 2
    fields = {"size on disk": f"{size:,} bytes ({size / 1e6:.3f} MB)"}
    for key in (
        "format",
        "version",
        "kind",
        "geometry",
        "n_points",
        "n_terms",
        "n_directions",
        "colour",
        "dtype",
    ):
        if key in header:
            fields[key] = header[key]
    if header.get("meta"):
        fields["meta"] = ", ".join(f"{k}={v}" for k, v in header["meta"].items())[:300]
    try:
        model = load_model(path)
    except ModelFileError as exc:
        fields["valid"] = f"no — {exc}"
        return fields, False
    physics = check_physics(model)
    fields["valid"] = (
        "yes (shapes, dtypes, finiteness, eq. (2), checksum, physical bounds)"
        if physics.ok
        else "no — the file is intact, but the model is not physical"
    )
    fields["physical"] = physics.describe()
    values = model.alpha.values
    fields["alpha"] = f"shape {model.alpha.shape}, range [{values.min():.3g}, {values.max():.3g}]"
    fields["total R_d (R,G,B)"] = "mean " + " ".join(f"{v:.4g}" for v in physics.total.mean(axis=0))
    fields["99.9% energy radius"] = (
        f"{np.min(physics.radius):.3g} … {np.max(physics.radius):.3g} mm (object {physics.size_mm:.3g} mm)"
    )
    return fields, physics.ok


acquire_app = typer.Typer(
    help="Virtual DISCO: simulate measurements by photon transport (Mitsuba 3 / Dr.Jit).",
    no_args_is_help=True,
)
app.add_typer(acquire_app, name="acquire")
app.add_typer(import_app, name="import")
acquire_app.command("photographs")(acquire_photographs_cmd)


@acquire_app.command("planar")
@user_errors
def acquire_planar_cmd(
    out: Path = typer.Option(..., "--out", "-o", help="Output data set (Zarr directory)."),
    material: str = typer.Option(
        None,
        "--material",
        "-m",
        help="Sample generator: homogeneous:<name>, marble, apple-slice, skin, fibers.",
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
    overwrite: bool = typer.Option(
        False,
        "--overwrite",
        help="Replace a data set of translucency made with other arguments (never anything else).",
    ),
    scheduler: str = _scheduler_option(),
    max_memory: str = _max_memory_option(),
    quiet: bool = _quiet_option(),
    as_json: bool = _json_option(),
):
    """Scan a pencil beam over a planar sample and record R_d around each incident point."""
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
    limit = _limit(max_memory)
    if (material is None) == (volume is None):
        raise TranslucencyError("give exactly one of --material NAME or --volume FILE.npz")
    if dtype not in ("float32", "float16"):
        raise TranslucencyError(f"--dtype: expected float32 or float16, got {dtype!r}")

    def need(voxels):
        n = resources.planar_acquisition(
            grid=grid, pitch=pitch, window=window, photons=photons, chunk=chunk, voxels=voxels, dtype=dtype
        )
        n.disk -= _bytes_at(out)  # a resumed acquisition keeps what is there
        return resources.check_resources("acquire planar", n, limit, out)

    if volume is None:  # before the sample is generated
        estimate = need(resources.slab_voxels(size, voxel))
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
    units = {
        "points": grid * grid,
        "photon_steps": estimate_seconds(vol, setup, steps_per_second=1.0, probe=walk),
        "pixels": grid * grid * setup.window_pixels() ** 2,
    }
    fresh = _bytes_at(out) == 0
    first = walk.seconds_per_step / resources.TIME_TERMS["acquire planar"]["photon_steps"]
    timing = resources.estimate_time(
        "acquire planar", units, (first, "from a probe of the walk on this sample")
    )
    _info(
        quiet,
        f"{grid * grid} incident points x {photons:,} photons x 3 channels on a "
        f"{' x '.join(f'{v:g}' for v in vol.size_mm)} mm slab; time {timing.text()}, "
        f"memory ~{estimate.memory / 2**20:,.0f} MiB",
    )
    t0 = time.perf_counter()
    with progress(quiet) as bar:
        task = bar.add_task("acquire", total=grid * grid, item="")
        acquire_planar(
            vol,
            setup,
            out,
            overwrite=overwrite,
            inputs=[volume],
            progress=lambda done, total: bar.update(task, completed=done, item="points"),
            scheduler=scheduler,
        )
    _calibrate("acquire planar", units, time.perf_counter() - t0, fresh)
    ds = open_dataset(out)
    summary = {
        "command": "acquire planar",
        "out": out,
        "points": ds.n_points,
        "window_pixels": ds.window,
        "photons": photons,
        "seed": seed,
        "complete": ds.complete(),
        "seconds": round(time.perf_counter() - t0, 3),
        "estimate": estimate.as_dict(),
        "time_estimate": timing.as_dict(),
    }
    _finish(as_json, quiet, summary, [f"data set: {out}"])


@acquire_app.command("mesh")
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
        help="Filling: homogeneous:<name>, marble (default), apple-slice, skin, fibers (object space).",
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
    overwrite: bool = typer.Option(
        False,
        "--overwrite",
        help="Replace a data set of translucency made with other arguments (never anything else).",
    ),
    scheduler: str = _scheduler_option(),
    max_memory: str = _max_memory_option(),
    quiet: bool = _quiet_option(),
    as_json: bool = _json_option(),
):
    """Pencil beams at surface points of a 3D object; exits tallied per vertex (R_d in mm^-2)."""
    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    check_option("--photons", photons, lo=1)
    check_option("--seed", seed, lo=0)
    check_option("--points", points, lo=1)
    check_option("--chunk", chunk, lo=1)
    check_option("--g", g, lo=-1, hi=1, open_lo=True, open_hi=True)
    check_option("--scale", scale, lo=0, open_lo=True)
    check_option("--voxel", voxel, lo=0, open_lo=True)

    limit = _limit(max_memory)
    if material is not None and volume is not None:
        raise TranslucencyError("give one of --material NAME or --volume FILE.npz, not both")
    claim_output(out, "mesh data set", overwrite=overwrite, inputs=[mesh, volume], reuse=True)
    obj = load_mesh(mesh, scale_mm=scale, up=up) if mesh is not None else make_pig()

    def need(voxels):
        n = resources.mesh_acquisition(
            vertices=len(obj.vertices),
            faces=len(obj.faces),
            points=min(points, len(obj.vertices)),
            photons=photons,
            chunk=chunk,
            voxels=voxels,
        )
        n.disk -= _bytes_at(out)  # a resumed acquisition keeps what is there
        return resources.check_resources("acquire mesh", n, limit, out)

    if volume is not None:
        vol = load_volume(volume)
        estimate = need(vol.sigma_s.size / 3)
    else:  # before the filling is generated
        estimate = need(float(np.prod([math.ceil(e / voxel) for e in obj.extents])))
        vol = object_volume(material or "marble", obj, voxel, g=g, seed=seed)
    P = min(points, len(obj.vertices))
    units = {"points": P, "photons": 3 * P * photons, "point_vertices": P * len(obj.vertices)}
    fresh = _bytes_at(out) == 0
    timing = _timed("acquire mesh", units)
    _info(
        quiet,
        f"{points} incident points x {photons:,} photons x 3 channels on a mesh of "
        f"{len(obj.vertices):,} vertices, {' x '.join(f'{v:.1f}' for v in obj.extents)} mm; "
        f"time {timing.text()}, memory ~{estimate.memory / 2**20:,.0f} MiB",
    )
    t0 = time.perf_counter()
    with progress(quiet) as bar:
        task = bar.add_task("acquire", total=points, item="")
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
            progress=lambda done, total: bar.update(task, completed=done, item="points"),
            scheduler=scheduler,
        )
    _calibrate("acquire mesh", units, time.perf_counter() - t0, fresh)
    ds = open_mesh_dataset(out)
    summary = {
        "command": "acquire mesh",
        "out": out,
        "points": ds.n_points,
        "vertices": len(obj.vertices),
        "photons": photons,
        "seed": seed,
        "complete": ds.complete(),
        "seconds": round(time.perf_counter() - t0, 3),
        "estimate": estimate.as_dict(),
        "time_estimate": timing.as_dict(),
    }
    _finish(as_json, quiet, summary, [f"mesh data set: {out}"])


@app.command()
@user_errors
def fit(
    data: Path = typer.Argument(..., help="A planar data set (.zarr directory)."),
    out: Path = typer.Option(..., "--out", "-o", help="Model file to write (.model.zip)."),
    model: str = typer.Option(
        "iso",
        "--model",
        help="iso | aniso (the paper's) | dipole | burley | pbd (photon beam diffusion) | ddipole "
        "(directional dipole at normal incidence).",
    ),
    terms: str = typer.Option(
        "3", "--terms", "-n", help="Exponential terms n per profile (1-4), or auto (held-out choice)."
    ),
    directions: str = typer.Option(
        "8",
        "--directions",
        "-m",
        help="Directions m of the anisotropic model (>= 2), or auto (m in 1, 2, 4, 8, 16 by held-out error).",
    ),
    weighting: str = typer.Option(
        "poisson",
        "--weighting",
        help="poisson: residuals weighted by the model's Poisson variance (more photons never hurt); "
        "relative: adds a 5 % relative error (the former default).",
    ),
    colour: str = typer.Option(
        None,
        "--colour",
        help="shared: the paper's (1, s_g, s_b) scale of one fall-off; per-channel: one fall-off "
        "per channel. Default: per-channel on planar data, shared on meshes.",
    ),
    exclusion: float = typer.Option(
        None, "--exclusion", help="Ignore pixels closer than this to x_i, mm (default one pixel)."
    ),
    rounds: int = typer.Option(3, "--rounds", help="Most alternation rounds (parameters, then alpha)."),
    chunk: int = typer.Option(
        None,
        "--chunk",
        help="Incident points read and fitted together, a task (default: an eighth of the points, "
        "128 to 512, in whole chunks of the store).",
    ),
    alpha_radius: float = typer.Option(
        None,
        "--alpha-radius",
        help="Pool alpha's statistics over the pixels (vertices) within this distance, mm. Default: alpha "
        "per pixel on planar data (dense scans), 12 mean edge lengths on meshes. For sparse grids of "
        "incident points or noisy data such as photographs (docs/rig.md).",
    ),
    float16: bool = typer.Option(False, "--float16", help="Store parameters as float16 (smaller file)."),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Replace an earlier output of translucency at --out (never anything else)."
    ),
    scheduler: str = _scheduler_option(),
    max_memory: str = _max_memory_option(),
    quiet: bool = _quiet_option(),
    as_json: bool = _json_option(),
):
    """Fit a model per incident point, with the modulation texture alpha, to a planar data set.

    An interrupted fit resumes from OUT.partial.npz when run again with the same arguments.
    """
    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    check_option("--rounds", rounds, lo=1)
    check_option("--exclusion", exclusion, lo=0)
    check_option("--chunk", chunk, lo=1)
    check_option("--alpha-radius", alpha_radius, lo=0)
    terms, directions = _count_or_auto("--terms", terms), _count_or_auto("--directions", directions)
    limit = _limit(max_memory)

    claim_output(out, "model file", overwrite=overwrite, inputs=[data], option="--out")
    workers = os.cpu_count() or 1
    if is_mesh_dataset(data):
        colour = colour or "shared"
        if terms == "auto":
            raise TranslucencyError("--terms: 'auto' selects on planar data only; give n for a mesh fit")
        if weighting != "poisson":
            raise TranslucencyError("--weighting: mesh fits weight by the Poisson variance only")
        check_fit_options(model, terms, 1, colour, weighting=weighting)
        ds = open_mesh_dataset(data)
        _refuse_damaged(ds)
        need = resources.mesh_fit(
            points=ds.n_points,
            vertices=int(ds.header["n_vertices"]),
            chunk=32,
            workers=workers,
            params=_params_per_point(model, terms, 1, colour),
        )
        resources.check_resources("fit", need, limit, out)
        return _fit_mesh_cmd(
            data,
            out,
            model,
            terms,
            colour,
            exclusion,
            rounds,
            float16,
            overwrite,
            quiet,
            as_json,
            need,
            scheduler,
            alpha_radius,
        )
    colour = colour or "per-channel"
    check_fit_options(model, terms, directions, colour, weighting=weighting)
    ds = open_dataset(data)
    _refuse_damaged(ds)
    chunk = None if chunk is None else min(chunk, ds.n_points)  # a chunk beyond the data is the data
    H, W = ds.window
    stored = int(ds.group["R_d"].chunks[0])
    need = resources.planar_fit(
        points=ds.n_points,
        pixels=H * W,
        chunk=chunk or default_chunk_points(ds.n_points, stored),
        workers=workers,
        params=_params_per_point(model, terms, directions, colour),
    )
    resources.check_resources("fit", need, limit, out)
    ckpt = out.with_name(out.name + ".partial.npz")
    candidates = (4 if terms == "auto" else 1) * (5 if directions == "auto" else 1)
    units = {"point_pixels": ds.n_points * H * W * rounds * candidates}
    timing = _timed(f"fit {model}", units)
    _info(quiet, f"fit {model} on {ds.n_points} incident points x {H * W:,} pixels; time {timing.text()}")
    fresh, t0 = not ckpt.exists(), time.perf_counter()
    with progress(quiet) as bar:
        task = bar.add_task(f"fit {model}", total=None, item="")

        def report(done, total, message):
            bar.update(task, completed=done, total=total or None, item=message)

        result = fit_planar(
            ds,
            model,
            n_terms=terms,
            n_directions=directions,
            colour=colour,
            exclusion_mm=exclusion,
            max_rounds=rounds,
            chunk_points=chunk,
            checkpoint=ckpt,
            progress=report,
            weighting=weighting,
            alpha_radius=alpha_radius,
            scheduler=scheduler,
        )
    _calibrate(f"fit {model}", units, time.perf_counter() - t0, fresh)
    path = save_model(
        result.model,
        out,
        dtype="float16" if float16 else "float32",
        meta={**result.metadata(data), "dataset_identity": dataset_identity(ds.header)},
        overwrite=overwrite,
    )
    if result.flagged.any():
        err_console.print(
            f"[yellow]warning:[/] {int(result.flagged.sum())} incident points have no usable data "
            f"(all masked, NaN or zero) and are flagged in the model: "
            f"{np.flatnonzero(result.flagged)[:10].tolist()}…"
        )
    bad = _warn_unphysical(path)
    summary = {**_fit_summary(path, result, data, bad, need), "time_estimate": timing.as_dict()}
    _finish(
        as_json, quiet, summary, [f"model: {path} ({result.seconds:.1f} s, {len(result.history)} rounds)"]
    )


def _params_per_point(model: str, terms: int, directions: int, colour: str) -> int:
    """Stored parameters per incident point of a fit (for the memory and size estimates)."""
    if model in ("dipole", "burley", "pbd", "ddipole"):
        return 6
    m = (16 if directions == "auto" else directions) if model == "aniso" else 1
    n = 4 if terms == "auto" else terms
    return (1 if colour == "shared" else 3) * m * n * 2 + 2


def _count_or_auto(option: str, value: str):
    """``auto`` or a whole number (the range is checked with the model: ``check_fit_options``)."""
    text = str(value).strip().lower()
    if text == "auto":
        return "auto"
    try:
        return int(text)
    except ValueError:
        raise TranslucencyError(f"{option}: expected a whole number or 'auto', got {value!r}") from None


def _refuse_damaged(ds) -> None:
    """One line for a data set with missing or undecodable chunks (``info`` lists them; re-running the
    acquisition with the same arguments repairs exactly those)."""
    damaged = ds.damaged_chunks()
    if damaged:
        listed = ", ".join(f"{k!r} chunks {v}" for k, v in damaged.items())
        raise TranslucencyError(
            f"{ds.path}: damaged data set ({listed} missing or undecodable); the acquisition is unfinished: "
            "re-run it with the same arguments to repair those chunks"
        )


def _fit_summary(path, result, data, unphysical, need) -> dict:
    return {
        "command": "fit",
        "model": path,
        "dataset": data,
        "kind": result.model.kind,
        "geometry": result.model.geometry,
        "n_points": result.model.n_points,
        "rounds": len(result.history),
        "objective_per_round": result.history,
        "seconds": round(result.seconds, 3),
        "flagged_points": np.flatnonzero(result.flagged).tolist(),
        "unphysical_points": unphysical,
        "estimate": need.as_dict(),
    }


def _warn_unphysical(path: Path) -> list[int]:
    """One warning line when the stored model breaks a physical bound (model/bounds.py); the points."""
    physics = read_header(path)["physics"]
    bad = sorted(set(physics["over_albedo"]) | set(physics["beyond_object"]))
    if bad:
        err_console.print(
            f"[yellow]warning:[/] {len(bad)} incident points are not physical (total reflectance up to "
            f"{physics['max_total_reflectance']:.3g}, energy radius up to "
            f"{physics['max_energy_radius_mm']:.3g} mm on a {physics['size_mm']:.3g} mm object): "
            f"{bad[:10]}{'…' if len(bad) > 10 else ''}; see `translucency info {path}`"
        )
    return bad


def _fit_mesh_cmd(
    data, out, model, terms, colour, exclusion, rounds, float16, overwrite, quiet, as_json, need, scheduler,
    alpha_radius=None,
):  # fmt: skip
    mds = open_mesh_dataset(data)
    units = {"point_pixels": mds.n_points * int(mds.header["n_vertices"]) * rounds}
    timing = _timed(f"fit {model}", units)
    _info(quiet, f"fit {model} on {mds.n_points} incident points x {int(mds.header['n_vertices']):,} "
          f"vertices; time {timing.text()}")  # fmt: skip
    t0 = time.perf_counter()
    with progress(quiet) as bar:
        task = bar.add_task(f"fit {model} per vertex", total=None, item="")
        result = fit_mesh(
            data,
            model,
            n_terms=terms,
            colour=colour,
            exclusion_mm=exclusion,
            max_rounds=rounds,
            alpha_radius=alpha_radius,
            progress=lambda done, total, msg: bar.update(task, completed=done, total=total or None, item=msg),
            scheduler=scheduler,
        )
    _calibrate(f"fit {model}", units, time.perf_counter() - t0)
    path = save_model(
        result.model,
        out,
        dtype="float16" if float16 else "float32",
        meta=result.metadata(Path(data).resolve()),
        overwrite=overwrite,
    )
    bad = _warn_unphysical(path)
    line = (
        f"model: {path} ({result.seconds:.1f} s, {len(result.history)} rounds, mesh of "
        f"{len(result.model.alpha.values):,} vertices)"
    )
    summary = {**_fit_summary(path, result, data, bad, need), "time_estimate": timing.as_dict()}
    _finish(as_json, quiet, summary, [line])


@app.command()
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
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Replace an earlier output of translucency at --out (never anything else)."
    ),
    max_memory: str = _max_memory_option(),
    quiet: bool = _quiet_option(),
    as_json: bool = _json_option(),
):
    """Relight a fitted object: irradiance per vertex, sparse transport, a picture through Mitsuba (EXR + PNG)."""  # noqa: E501 — Typer lists the docstring verbatim as the command's one-line help; a line break would show in `translucency --help`
    check_option("--spp", spp, lo=1)
    check_option("--radius", radius, lo=1e-6, hi=1e9)  # 1 nm to 1000 km (the far field divides by r²)
    for value in size:
        check_option("--size", value, lo=1, hi=16384)
    limit = _limit(max_memory)

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
    if radius is None:  # as the transport chooses it (render/transport.py)
        fit_pairs = math.sqrt(0.5 * 2.5e7 * mesh.area / (math.pi * V**2))
        rad = float(min(np.max(m.energy_radius(0.99)), fit_pairs))
    else:
        rad = float(radius)
    need = resources.rendering(
        vertices=V,
        surface_mm2=float(mesh.area),
        radius_mm=rad,
        width=size[0],
        height=size[1],
        reference=reference,
        spp_reference=spp,
    )
    resources.check_resources("render", need, limit, out)
    claim_folder(out, overwrite=overwrite, inputs=[model, header.get("meta", {}).get("dataset") or None])
    units = {
        "vertices": V,
        "pairs": min(2.5e7, V**2, V + V**2 * math.pi * min(rad, 1e9) ** 2 / max(float(mesh.area), 1e-12)),
        "samples": 16 * size[0] * size[1],
        "reference_samples": 2 * size[0] * size[1] * spp if reference else 0,
    }
    timing = _timed("render", units)
    _info(quiet, f"render of {V:,} vertices at {size[0]} x {size[1]}; time {timing.text()}")
    t0 = time.perf_counter()
    cam = Camera.looking_at(mesh, direction, *size)
    if abs(direction[2]) > 0.999:  # looking straight up or down: the image's up is +y, not +z
        cam = dataclasses.replace(cam, up=(0.0, 1.0, 0.0))
    vol = volume_of_dataset(mesh, dheader) if reference else None
    with progress(quiet) as bar:
        task = bar.add_task("render", total=4 if reference else 3, item="")
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
            progress=lambda done, total, name: bar.update(task, completed=done, total=total, item=name),
        )
        bar.update(task, completed=4 if reference else 3, item="done")
    _calibrate("render", units, time.perf_counter() - t0, not res.get("reference_cached", False))
    table = Table(title=f"render of {model.name}", show_header=False)
    for k, v in res.items():
        table.add_row(k, f"{v:.4g}" if isinstance(v, float) else str(v))
    summary = {
        "command": "render",
        "model": model,
        "images": out,
        **res,
        "estimate": need.as_dict(),
        "time_estimate": timing.as_dict(),
        "seconds": round(time.perf_counter() - t0, 3),
    }
    _finish(as_json, quiet, summary, [table, f"images: {out}"])


@app.command()
@user_errors
def evaluate(
    model: Path = typer.Argument(..., help="The model file to evaluate (.model.zip)."),
    data: Path = typer.Argument(..., help="The planar data set it was fitted to (.zarr directory)."),
    report: Path = typer.Option(Path("report"), "--report", help="Directory for the figures and index.html."),
    json_out: Path = typer.Option(
        None,
        "--json",
        help="Write the error summary (rel_l2, rel_l2_near/mid/far) here; '-': print it as one JSON "
        "object on stdout (for scripts).",
    ),
    compare: list[Path] = typer.Option(
        None, "--compare", help="Other model files of the same data (repeatable)."
    ),
    points: str = typer.Option(None, "--points", help="Incident points for the profiles, e.g. '0,17,40'."),
    truth: Path = typer.Option(
        None,
        "--truth",
        help="An independent acquisition of the same incident points (another seed, more photons): "
        "errors against it, with the in-sample errors beside.",
    ),
    overwrite: bool = typer.Option(
        False, "--overwrite", help="Replace an earlier output of translucency at --out (never anything else)."
    ),
    scheduler: str = _scheduler_option(),
    max_memory: str = _max_memory_option(),
    quiet: bool = _quiet_option(),
):
    """Relative L2 errors (overall, per distance band, energy-weighted), error maps, profiles, HTML report."""
    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work

    limit = _limit(max_memory)
    to_stdout = json_out is not None and str(json_out) == "-"
    json_out = None if to_stdout else json_out
    models, flagged, exclusion, metas = {}, {}, {}, {}
    for path in [model, *(compare or [])]:
        m = load_model(path)
        meta = read_header(path).get("meta", {})
        metas[path] = meta if isinstance(meta, dict) else {}
        fl = meta.get("flagged_points", [])
        name = model_label(m)
        name = name if name not in models else f"{name} ({path.name})"
        models[name] = m
        exclusion[name] = meta.get("fit", {}).get("exclusion_mm")  # evaluate where the fit looked
        mask = np.zeros(m.n_points, bool)
        mask[np.asarray(fl, dtype=int)] = True
        flagged[name] = mask
    try:
        picks = None if points is None else [int(v) for v in points.split(",") if v.strip()]
    except ValueError:
        raise TranslucencyError(f"--points: expected comma-separated integers, got {points!r}") from None
    ds = open_dataset(data)
    for p in picks or []:
        if not 0 <= p < ds.n_points:
            raise TranslucencyError(
                f"--points: {p} is not an incident point of {data} (0..{ds.n_points - 1})"
            )
    H, W = ds.window
    need = resources.evaluation(
        points=ds.n_points,
        pixels=H * W,
        params=[int(np.prod(_param_shape(m))) for m in models.values()],
        datasets=2 if truth is not None else 1,
    )
    resources.check_resources("evaluate", need, limit, report)
    _warn_other_sample(metas, ds, truth)
    inputs = [model, data, *(compare or []), truth]
    if json_out is not None:
        claim_output(json_out, "json summary", overwrite=overwrite, inputs=inputs, option="--json")
    claim_folder(report, overwrite=overwrite, inputs=inputs, option="--report")
    d = 2 if truth is not None else 1
    units = {
        "point_pixels": ds.n_points * H * W * d,
        "model_pixels": len(models) * ds.n_points * H * W * d,
        "param_pixels": sum(int(np.prod(_param_shape(m))) for m in models.values()) * ds.n_points * H * W * d,
        "models": len(models),
    }
    timing = _timed("evaluate", units)
    _info(quiet, f"{len(models)} model(s) on {ds.n_points} points x {H} x {W} pixels; time {timing.text()}")
    t0 = time.perf_counter()
    summary = write_report(
        models,
        ds,
        report,
        points=picks,
        flagged=flagged,
        json_path=json_out,
        truth=truth,
        exclusion=exclusion,
        scheduler=scheduler,
    )
    title = (
        f"relative L2 error against the truth {truth}"
        if truth
        else f"relative L2 error on {data} (in-sample)"
    )
    table = Table(title=title)
    columns = ["model", "all", "near <1 mm", "mid 1-4 mm", "far >4 mm", "total refl."]
    table_columns = columns + (["in-sample all"] if truth else [])
    for col in table_columns:
        table.add_column(col)
    for name, s in summary["models"].items():
        cells = [f"{100 * s[k]:.2f} %" for k in ("rel_l2", "rel_l2_near", "rel_l2_mid", "rel_l2_far")]
        cells.append(f"{100 * s['energy_error']['total']:.2f} %")
        if truth:
            cells.append(f"{100 * s['in_sample']['rel_l2']:.2f} %")
        table.add_row(name, *cells)
    nf = summary["noise_floor"]
    table.add_row(
        "[dim]the truth's noise[/]" if truth else "[dim]noise alone[/]",
        *(f"[dim]{100 * nf[k]:.2f} %[/]" for k in ("all", "near", "mid", "far")),
    )
    seconds = time.perf_counter() - t0
    _calibrate("evaluate", units, seconds)
    summary = {"command": "evaluate", "report": report / "index.html", **summary, "estimate": need.as_dict()}
    summary.update(seconds=round(seconds, 3), time_estimate=timing.as_dict())
    _finish(to_stdout, quiet, summary, [table, f"report: {report / 'index.html'}"])


def _param_shape(m) -> tuple:
    """Parameters per incident point of a model (for the memory estimate)."""
    if m.kind == "exponential":
        return tuple(m.c.shape[1:]) + (2,)
    return (6,)


def _identity_of_model(meta: dict):
    """The identity of the data set a model was fitted to: recorded, or read from its acquisition header
    (mesh fits), or from the data set at the recorded path if it is still there (older model files)."""
    if isinstance(meta.get("dataset_identity"), dict):
        return meta["dataset_identity"]
    if isinstance(meta.get("acquisition"), dict):
        return dataset_identity(meta["acquisition"])
    recorded = meta.get("dataset")
    if isinstance(recorded, str) and recorded and Path(recorded).is_dir():
        try:
            opened = open_mesh_dataset(recorded) if is_mesh_dataset(recorded) else open_dataset(recorded)
        except TranslucencyError:
            return None
        return dataset_identity(opened.header)
    return None


def _warn_other_sample(metas: dict, ds, truth) -> None:
    """A warning line for a model fitted to data of another sample than ``ds`` (and for a truth of another
    sample): the errors would compare two materials."""
    own = dataset_identity(ds.header)
    for path, meta in metas.items():
        theirs = _identity_of_model(meta)
        if theirs is not None and theirs != own:
            err_console.print(
                f"[yellow]warning:[/] {path} was fitted to data of another sample than {ds.path} "
                f"(fitted to {meta.get('dataset', '?')}); its errors compare two materials",
                highlight=False,
                soft_wrap=True,
            )
    if truth is not None:
        other = dataset_identity(open_dataset(truth).header)
        if other != own:
            err_console.print(
                f"[yellow]warning:[/] --truth {truth} measured another sample than {ds.path} (a generated "
                "sample is set by --sample-seed, default --seed); the errors compare two materials",
                highlight=False,
                soft_wrap=True,
            )


#: what --help shows for each kind of value (Typer would print <float>, <bool>, ...)
_METAVARS = {
    "Path": "PATH",
    "int": "INT",
    "float": "FLOAT",
    "str": "TEXT",
    "bool": "",
    "list[str]": "TEXT",
    "list[Path]": "PATH",
    "tuple[int, int]": "W H",
    "tuple[float, float, float]": "W H T",
}


def _name_metavars(*typer_apps) -> None:
    """Give every option of every command a real metavar (FLOAT, PATH, ...) unless it has one."""
    for typer_app in typer_apps:
        for command in typer_app.registered_commands:
            for param in inspect.signature(command.callback).parameters.values():
                info = param.default
                if isinstance(info, typer.models.OptionInfo) and info.metavar is None:
                    info.metavar = _METAVARS.get(str(param.annotation))


_name_metavars(app, acquire_app, import_app)


def main() -> None:
    """Console entry point."""
    app()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
