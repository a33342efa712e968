"""``translucency import object``: a lab's multi-view HDR photographs of a laser stepped over a scanned
object (with the cameras' calibration) as a mesh data set that ``fit``, ``render``, ``info`` and the report
read as they read ``acquire mesh``'s."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import (
    chunk_option,
    dataset_overwrite_option,
    finish,
    json_option,
    max_memory_option,
    quiet_option,
    user_errors,
)
from ._run import RichReporter


@user_errors
def import_object_cmd(
    rig: Path = typer.Argument(
        ...,
        help="The rig file object.json (or its folder): mesh, cameras, shots (documentation: 'The object "
        "rig's files').",
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Output mesh data set (Zarr directory)."),
    exit_law: str = typer.Option(
        None,
        "--exit-law",
        help="Radiance to exitance: lambertian (pi L), dielectric (F_t/(1 - F_dr) of the boundary's eta), "
        "walk (photon walks at each shot's fitted material, per cell and camera) or from-views; default "
        "the rig file's.",
    ),
    chunk: int = chunk_option(8),
    overwrite: bool = dataset_overwrite_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Import multi-view photographs of a laser scanned over a real object as a mesh data set."""
    from ..workflow.importing import import_object  # heavy: Mitsuba, OpenCV and trimesh load when it runs

    ds = import_object(
        rig,
        out,
        exit_law=exit_law,
        chunk_points=chunk,
        overwrite=overwrite,
        max_memory=max_memory,
        reporter=RichReporter(quiet),
    )
    s = ds.summary
    errors = ", ".join(f"{c['name']} {_pose_check(c['reprojection_px'])}" for c in s["cameras"])
    line = (
        f"mesh data set: {out} ({s['points']} shots x {s['vertices']:,} vertices; poses {errors}; "
        f"exit law {s['exit_law']['law']}; unseen {s['flags']['unseen']:,} pairs filled; "
        f"saturated {s['flags']['saturated']:,} pairs ({s['saturated_views']:,} views dropped), "
        f"spot {s['flags']['spot']:,}: {s['near_peak']:,} from the near-peak model; "
        f"a shot's energy uncertain by {_uncertainty(_worst_share(s['energy_sigma'], s['energy']))})"
    )
    finish(as_json, quiet, s, [line])


def _worst_share(sigma, energy) -> float:
    """The largest σ_E / E over shots and channels (0 for no shot)."""
    shares = [s / max(e, 1e-30) for ss, ee in zip(sigma, energy) for s, e in zip(ss, ee)]
    return max(shares, default=0.0)


def _uncertainty(share: float) -> str:
    """The worst σ_E / E in words: a percentage, or — beyond 100 % — that the energy is not measured.

    Examples
    --------
    >>> _uncertainty(0.034)
    'up to 3% (1 σ)'
    >>> _uncertainty(4e24)
    'more than its value in one shot and channel (σ_E/E up to 4e+24): too noisy to measure it'
    """
    if share <= 1.0:
        return f"up to {share:.0%} (1 σ)"
    return f"more than its value in one shot and channel (σ_E/E up to {share:.3g}): too noisy to measure it"


def _pose_check(report: dict) -> str:
    """What checked a camera's pose: its marks' reprojection error and its laser spots' miss, px (a pose
    given as R, t has no marks; a camera that sees no hit, no spots)."""
    parts = [
        f"{what} {report[key]:.2f} px"
        for key, what in (("pose", "marks"), ("laser_spot", "spots"))
        if key in report
    ]
    return " / ".join(parts) or "given, unchecked"
