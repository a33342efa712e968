"""``translucency import images``: a real rig's HDR photographs of a scanned laser spot, with the camera
calibration, as a planar data set the fitter reads."""

from __future__ import annotations

from pathlib import Path

import typer

from .._validate import TranslucencyError
from ._common import (
    PANEL_CAMERA,
    PANEL_OUTPUT,
    PANEL_RUN,
    PANEL_SAMPLE,
    PANEL_SCAN,
    chunk_option,
    finish,
    json_option,
    max_memory_option,
    quiet_option,
    scheduler_option,
    user_errors,
)
from ._run import RichReporter

app = typer.Typer(
    help="Import measurements of a real rig as data sets the fitter reads.", no_args_is_help=True
)


def _parse_camera(text: str) -> tuple[Path, Path, Path]:
    """``--extra-camera FOLDER,POSITIONS,CALIBRATION`` → three paths (the library checks that they exist)."""
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) != 3 or not all(parts):
        raise TranslucencyError(f"--extra-camera: expected FOLDER,POSITIONS,CALIBRATION, got {text!r}")
    folder, positions, calibration = (Path(p) for p in parts)
    return folder, positions, calibration


class ImagesOptions:
    """The options of ``import images`` (a class of their own keeps the command short)."""

    folder = typer.Argument(
        ..., help="Folder of images, one (or a bracket / repeated frames) per laser position."
    )
    positions = typer.Option(
        ...,
        "--positions",
        "-p",
        help="CSV or JSON table: file, x, y (mm) or u, v (px), power (W), exposure (s).",
    )
    calibration = typer.Option(
        ...,
        "--calibration",
        "-c",
        help="JSON: homography | points | checkerboard, scale or reference, dark, flat, ...",
    )
    out = typer.Option(..., "--out", "-o", help="Output planar data set (Zarr directory).")
    gain = typer.Option(
        None,
        "--gain",
        help="Pixel value per unit exitance (W/mm^2) per second; overrides the calibration's scale.",
    )
    pitch = typer.Option(
        0.25, "--pitch", help="Pixel size of the windows on the sample, mm.", rich_help_panel=PANEL_SCAN
    )
    window = typer.Option(
        8.0, "--window", help="Window side around each incident point, mm.", rich_help_panel=PANEL_SCAN
    )
    supersample = typer.Option(
        3,
        "--supersample",
        help="Sub-samples per output pixel side (area average).",
        rich_help_panel=PANEL_SCAN,
    )
    specular_radius = typer.Option(
        0.0,
        "--specular-radius",
        help="Mask pixels this close to the laser, mm (direct reflection).",
        rich_help_panel=PANEL_CAMERA,
    )
    dilate = typer.Option(
        1, "--dilate", help="Grow the saturated mask by this many image pixels.", rich_help_panel=PANEL_CAMERA
    )
    floor = typer.Option(
        None,
        "--floor",
        help="Mask pixel values below this after the dark frame.",
        rich_help_panel=PANEL_CAMERA,
    )
    sample_size = typer.Option(
        None,
        "--sample-size",
        help="Sample width,height in mm (e.g. 20,20): pixels outside are masked.",
        rich_help_panel=PANEL_SAMPLE,
    )
    eta = typer.Option(
        1.3, "--eta", help="Relative index of refraction of the sample.", rich_help_panel=PANEL_SAMPLE
    )
    beam_rms = typer.Option(
        0.0,
        "--beam-rms",
        help="The laser beam's rms radius on the sample, mm (sqrt of the mean squared distance of its "
        "irradiance from its centre; a uniform disc of radius b has b/sqrt(2)). Windows are corrected to a "
        "pencil beam's response by its second moment. Default 0: a pencil beam, no correction.",
        rich_help_panel=PANEL_SCAN,
    )
    chunk = chunk_option(16)
    dtype = typer.Option(
        "float32",
        "--dtype",
        help="Storage of R_d and variance: float32 or float16.",
        rich_help_panel=PANEL_OUTPUT,
    )
    extra_camera = typer.Option(
        None,
        "--extra-camera",
        help="Another camera's photographs of the same laser positions, with its own table and calibration "
        "(repeatable): the cameras are averaged onto the same windows where all of them are valid — two "
        "cameras on opposite sides cancel the slant of light leaving obliquely.",
        rich_help_panel=PANEL_CAMERA,
    )
    overwrite = typer.Option(
        False,
        "--overwrite",
        help="Replace a data set of translucency made from other inputs (never anything else).",
        rich_help_panel=PANEL_RUN,
    )
    scheduler = scheduler_option()
    max_memory = max_memory_option()
    quiet = quiet_option()
    as_json = json_option()


@app.command("images")
@user_errors
def import_images_cmd(
    folder: Path = ImagesOptions.folder,
    positions: Path = ImagesOptions.positions,
    calibration: Path = ImagesOptions.calibration,
    out: Path = ImagesOptions.out,
    gain: float = ImagesOptions.gain,
    pitch: float = ImagesOptions.pitch,
    window: float = ImagesOptions.window,
    supersample: int = ImagesOptions.supersample,
    specular_radius: float = ImagesOptions.specular_radius,
    dilate: int = ImagesOptions.dilate,
    floor: float = ImagesOptions.floor,
    sample_size: str = ImagesOptions.sample_size,
    eta: float = ImagesOptions.eta,
    beam_rms: float = ImagesOptions.beam_rms,
    dtype: str = ImagesOptions.dtype,
    extra_camera: list[str] = ImagesOptions.extra_camera,
    chunk: int = ImagesOptions.chunk,
    overwrite: bool = ImagesOptions.overwrite,
    scheduler: str = ImagesOptions.scheduler,
    max_memory: str = ImagesOptions.max_memory,
    quiet: bool = ImagesOptions.quiet,
    as_json: bool = ImagesOptions.as_json,
):
    """Import HDR photographs of a scanned laser spot (with the camera calibration) as a planar data set."""
    from ..workflow.importing import import_images  # heavy: Dask, SciPy and scikit-image load when it runs

    ds = import_images(
        folder,
        positions,
        calibration,
        out,
        overwrite=overwrite,
        extra_cameras=[_parse_camera(text) for text in extra_camera or ()],
        gain=gain,
        scheduler=scheduler,
        max_memory=max_memory,
        reporter=RichReporter(quiet),
        pitch=pitch,
        window=window,
        supersample=supersample,
        specular_radius=specular_radius,
        dilate=dilate,
        floor=floor,
        sample_size=sample_size,
        eta=eta,
        chunk_points=chunk,
        dtype=dtype,
        beam_rms=beam_rms,
    )
    s, rms = ds.summary, ds.summary["rms_px"]
    line = (
        f"data set: {out} ({s['points']} points, windows {s['window_pixels'][0]} x {s['window_pixels'][1]} "
        f"at {s['pitch']} mm" + (f"; marked points fit to {rms:.3f} px rms" if rms is not None else "") + ")"
    )
    finish(as_json, quiet, s, [line])
