"""``translucency fit``: a model per incident point, with the modulation texture α, to a planar or a mesh
data set."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import (
    finish,
    json_option,
    max_memory_option,
    overwrite_option,
    quiet_option,
    scheduler_option,
    user_errors,
)
from ._run import RichReporter


@user_errors
def fit(
    data: Path = typer.Argument(
        ...,
        help="A planar or a mesh data set (.zarr directory, from acquire planar|mesh or import images).",
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Model file to write (.model.zip)."),
    model: str = typer.Option(
        "iso",
        "--model",
        help="iso | aniso (the paper's; planar data sets only) | dipole | burley | pbd (photon beam "
        "diffusion) | ddipole (directional dipole at normal incidence).",
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
    overwrite: bool = overwrite_option(),
    scheduler: str = scheduler_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Fit a model per incident point, with the modulation texture alpha, to a planar or a mesh data set.

    An interrupted fit resumes from OUT.partial.npz when run again with the same arguments.
    """
    from ..workflow.fitting import (
        fit_model,
    )  # heavy: the fitter loads Dask, SciPy and Numba only when it runs

    fitting = fit_model(
        data,
        model,
        out,
        n_terms=terms,
        n_directions=directions,
        colour=colour,
        weighting=weighting,
        max_rounds=rounds,
        exclusion_mm=exclusion,
        alpha_radius=alpha_radius,
        chunk_points=chunk,
        float16=float16,
        overwrite=overwrite,
        scheduler=scheduler,
        max_memory=max_memory,
        reporter=RichReporter(quiet),
    )
    s = fitting.summary
    mesh_of = f", mesh of {len(fitting.model.alpha.values):,} vertices" if s["geometry"] == "mesh" else ""
    line = f"model: {fitting.path} ({s['seconds']:.1f} s, {s['rounds']} rounds{mesh_of})"
    finish(as_json, quiet, s, [line])
