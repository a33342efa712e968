"""``translucency import images`` and ``translucency acquire photographs``: a real rig, and a virtual one.

Registered in :mod:`translucency.cli.app` (``app.add_typer(import_app, name="import")`` and
``acquire_app.command("photographs")(acquire_photographs_cmd)``).  A user's mistake prints one
``error:`` line and exits with status 2, as every command of the tool.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import typer
from rich.console import Console

from .._validate import TranslucencyError, check_option
from ..acquire import load_volume, make_sample
from ..cluster import parse_scheduler
from ..io.outputs import claim_folder, claim_output
from ..rig.calibration import load_calibration
from ..rig.importer import ImportSetup, import_images
from ._flags import cli_words
from ._options import scheduler_option

console = Console()
err_console = Console(stderr=True)

import_app = typer.Typer(
    help="Import measurements of a real rig as data sets the fitter reads.", no_args_is_help=True
)


def _user_errors(func):
    """A :class:`TranslucencyError` → one ``error:`` line and exit status 2 (as ``cli.app.user_errors``)."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except TranslucencyError as exc:
            err_console.print(f"[bold red]error:[/] {cli_words(str(exc))}", highlight=False, soft_wrap=True)
            raise typer.Exit(2) from None

    return wrapper


def _parse_view(text: str) -> tuple[Path, Path, Path]:
    """``--view FOLDER,POSITIONS,CALIBRATION`` → three paths, each checked to exist."""
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) != 3 or not all(parts):
        raise TranslucencyError(f"--view: expected FOLDER,POSITIONS,CALIBRATION, got {text!r}")
    folder, positions, calibration = (Path(p) for p in parts)
    for what, path in (("folder", folder), ("positions", positions), ("calibration", calibration)):
        if not path.exists():
            raise TranslucencyError(f"--view: {what} {path}: no such file or folder")
    return folder, positions, calibration


@import_app.command("images")
@_user_errors
def import_images_cmd(
    folder: Path = typer.Argument(
        ..., help="Folder of images, one (or a bracket / repeated frames) per laser position."
    ),
    positions: Path = typer.Option(
        ...,
        "--positions",
        "-p",
        help="CSV or JSON table: file, x, y (mm) or u, v (px), power (W), exposure (s).",
    ),
    calibration: Path = typer.Option(
        ...,
        "--calibration",
        "-c",
        help="JSON: homography | points | checkerboard, scale or reference, dark, flat, ...",
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Output planar data set (Zarr directory)."),
    scale: float = typer.Option(
        None,
        "--scale",
        help="Pixel value per unit exitance (W/mm^2) per second; overrides the calibration's.",
    ),
    pitch: float = typer.Option(0.25, "--pitch", help="Pixel size of the windows on the sample, mm."),
    window: float = typer.Option(8.0, "--window", help="Window side around each incident point, mm."),
    supersample: int = typer.Option(
        3, "--supersample", help="Sub-samples per output pixel side (area average)."
    ),
    specular_radius: float = typer.Option(
        0.0, "--specular-radius", help="Mask pixels this close to the laser, mm (direct reflection)."
    ),
    dilate: int = typer.Option(1, "--dilate", help="Grow the saturated mask by this many image pixels."),
    floor: float = typer.Option(None, "--floor", help="Mask pixel values below this after the dark frame."),
    sample_size: str = typer.Option(
        None, "--sample-size", help="Sample width,height in mm (e.g. 20,20): pixels outside are masked."
    ),
    eta: float = typer.Option(1.3, "--eta", help="Relative index of refraction of the sample."),
    beam_rms: float = typer.Option(
        0.0,
        "--beam-rms",
        help="The laser beam's rms radius on the sample, mm (sqrt of the mean squared distance of its "
        "irradiance from its centre; a uniform disc of radius b has b/sqrt(2)). Windows are corrected to a "
        "pencil beam's response by its second moment. Default 0: a pencil beam, no correction.",
    ),
    chunk: int = typer.Option(16, "--chunk", help="Incident points per chunk (unit of resuming)."),
    dtype: str = typer.Option("float32", "--dtype", help="Storage of R_d and variance: float32 or float16."),
    view: list[str] = typer.Option(
        None,
        "--view",
        metavar="FOLDER,POSITIONS,CALIBRATION",
        help="Another camera's photographs of the same laser positions, with its own table and calibration "
        "(repeatable): the views are averaged onto the same windows where all of them are valid — two "
        "cameras on opposite sides cancel the slant of light leaving obliquely.",
    ),
    overwrite: bool = typer.Option(
        False,
        "--overwrite",
        help="Replace a data set of translucency made from other inputs (never anything else).",
    ),
    scheduler: str = scheduler_option(),
):
    """Import HDR photographs of a scanned laser spot (with the camera calibration) as a planar data set."""
    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    for name, value in (("--pitch", pitch), ("--window", window)):
        check_option(name, value, lo=0, open_lo=True)
    check_option("--supersample", supersample, lo=1, hi=16)
    check_option("--specular-radius", specular_radius, lo=0)
    check_option("--dilate", dilate, lo=0)
    check_option("--chunk", chunk, lo=1)
    check_option("--beam-rms", beam_rms, lo=0)
    check_option("--eta", eta, lo=0, open_lo=True)
    if scale is not None:
        check_option("--scale", scale, lo=0, open_lo=True)
    views = [_parse_view(text) for text in view or ()]
    view_inputs = [p for v in views for p in v]
    claim_output(
        out,
        "planar data set",
        overwrite=overwrite,
        inputs=[folder, positions, calibration, *view_inputs],
        reuse=True,
    )
    if not calibration.is_file():
        raise TranslucencyError(f"--calibration {calibration}: no such file")
    calib = load_calibration(calibration)
    if scale is not None:
        calib.scale = scale
    other_views = []
    for v_folder, v_positions, v_calibration in views:
        v_calib = load_calibration(v_calibration)
        if scale is not None:
            v_calib.scale = scale
        other_views.append((v_folder, v_positions, v_calib))
    size = None
    if sample_size is not None:
        try:
            size = tuple(float(v) for v in sample_size.split(","))
        except ValueError:
            size = ()
        if len(size) != 2 or not all(np.isfinite(v) and v > 0 for v in size):
            raise TranslucencyError(f"--sample-size: expected width,height in mm, got {sample_size!r}")
    setup = ImportSetup(
        pitch=pitch,
        window=window,
        supersample=supersample,
        specular_radius=specular_radius,
        dilate=dilate,
        floor=floor,
        sample_size=size,
        eta=eta,
        chunk_points=chunk,
        dtype=dtype,
        beam_rms=beam_rms,
    )
    ds = import_images(
        folder,
        positions,
        calib,
        out,
        setup,
        overwrite=overwrite,
        inputs=[calibration, *(v[2] for v in views)],
        views=other_views,
        scheduler=scheduler,
    )
    rms = calib.source.get("rms_px")
    console.print(
        f"data set: {out} ({ds.n_points} points, windows {ds.window[0]} x {ds.window[1]} at {ds.pitch} mm"
        + (f"; marked points fit to {rms:.3f} px rms" if rms is not None else "")
        + ")"
    )


@_user_errors
def acquire_photographs_cmd(
    out: Path = typer.Option(
        ..., "--out", "-o", help="Output folder: images, positions.csv, calibration.json."
    ),
    material: str = typer.Option(
        None,
        "--material",
        "-m",
        help="Sample generator: homogeneous:<name>, marble, apple-slice, skin, fibers.",
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
    from ..acquire import PlanarSetup
    from ..rig.photographs import VirtualCamera, photograph_sample

    check_option("--grid", grid, lo=1, hi=64)
    check_option("--spp", spp, lo=1)
    check_option("--fov", fov, lo=1, hi=120)
    for v in resolution:
        check_option("--resolution", v, lo=8, hi=8192)
    if (material is None) == (volume is None):
        raise TranslucencyError("give exactly one of --material NAME or --volume FILE.npz")
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
