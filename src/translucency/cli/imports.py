"""``translucency import images``: a real rig's HDR photographs of a scanned laser spot, with the camera
calibration, as a planar data set the fitter reads."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from .._validate import TranslucencyError, check_option
from ..io.dataset import open_dataset
from ..io.outputs import claim_output
from ._common import console, scheduler_option, user_errors
from ._run import keeping, kept_chunks

app = typer.Typer(
    help="Import measurements of a real rig as data sets the fitter reads.", no_args_is_help=True
)


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


@app.command("images")
@user_errors
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
    from ..cluster import parse_scheduler  # heavy: Dask, SciPy and scikit-image load only when it runs
    from ..rig.planar import ImportSetup, import_images, load_calibration

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
    with keeping(lambda: kept_chunks(out, open_dataset)):  # Ctrl-C: the chunks kept, and how to resume
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
