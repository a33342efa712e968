"""``translucency fit``: a model per incident point, with the modulation texture α, to a planar or a mesh
data set."""

from __future__ import annotations

from pathlib import Path

import typer

from .._validate import TranslucencyError
from ._common import (
    PANEL_FITTING,
    PANEL_MODEL,
    PANEL_OUTPUT,
    PANEL_RUN,
    finish,
    json_option,
    max_memory_option,
    overwrite_option,
    quiet_option,
    scheduler_option,
    user_errors,
)
from ._run import RichReporter

# -- the options (their help is what --help shows) --------------------------------------------------
_DATA = typer.Argument(
    ...,
    help="A planar or a mesh data set (.zarr directory, from acquire planar|mesh or import images).",
)
_OUT = typer.Option(..., "--out", "-o", help="Model file to write (.model.zip).")
_MODEL = typer.Option(
    "auto",
    "--model",
    help="auto: the sum of exponentials with its structure (colour, terms, directions) chosen by held-out "
    "error on the data's own photons | iso | aniso (the paper's; planar data sets only) | dipole | burley "
    "| pbd (photon beam diffusion) | ddipole (directional dipole at normal incidence).",
)
_TERMS = typer.Option(
    None,
    "--terms",
    "-n",
    help="Exponential terms n per profile (1-4), or auto (held-out choice). Default: chosen with "
    "--model auto, 3 otherwise.",
    rich_help_panel=PANEL_MODEL,
)
_DIRECTIONS = typer.Option(
    None,
    "--directions",
    help="Directions m of the anisotropic model (>= 2), or auto (m in 1, 2, 4, 8, 16 by held-out error). "
    "Default: chosen with --model auto, 8 with --model aniso (the paper's).",
    rich_help_panel=PANEL_MODEL,
)
_WEIGHTING = typer.Option(
    "poisson",
    "--weighting",
    help="poisson: residuals weighted by the model's Poisson variance (more photons never hurt); "
    "relative: the data's variance with a 5 % relative error added (its share grows with the photons).",
    rich_help_panel=PANEL_FITTING,
)
_COLOUR = typer.Option(
    None,
    "--colour",
    help="shared: the paper's (1, s_g, s_b) scale of one fall-off; per-channel: one fall-off per "
    "channel; auto: the held-out choice. Default: chosen with --model auto, per-channel otherwise.",
    rich_help_panel=PANEL_MODEL,
)
_EXCLUSION = typer.Option(
    None,
    "--exclusion",
    help="Ignore pixels closer than this to x_i, mm (default one pixel).",
    rich_help_panel=PANEL_FITTING,
)
_ROUNDS = typer.Option(
    3, "--rounds", help="Most alternation rounds (parameters, then alpha).", rich_help_panel=PANEL_FITTING
)
_CHUNK = typer.Option(
    None,
    "--chunk",
    help="Incident points read and fitted together, a task (default: an eighth of the points, "
    "128 to 512, in whole chunks of the store).",
    rich_help_panel=PANEL_RUN,
)
_ALPHA_RADIUS = typer.Option(
    None,
    "--alpha-radius",
    help="Pool alpha's statistics over the pixels (vertices) within this distance, mm. Default: alpha "
    "per pixel on planar data (dense scans), 12 mean edge lengths on meshes (at least 4 mm). For sparse "
    "grids of incident points or noisy data such as photographs (documentation: 'Photograph and calibrate a "
    "flat sample').",
    rich_help_panel=PANEL_FITTING,
)
_DTYPE = typer.Option(
    "float32",
    "--dtype",
    help="Storage of the parameters: float32 or float16 (a smaller file).",
    rich_help_panel=PANEL_OUTPUT,
)


@user_errors
def fit(
    data: Path = _DATA,
    out: Path = _OUT,
    model: str = _MODEL,
    terms: str = _TERMS,
    directions: str = _DIRECTIONS,
    weighting: str = _WEIGHTING,
    colour: str = _COLOUR,
    exclusion: float = _EXCLUSION,
    rounds: int = _ROUNDS,
    alpha_radius: float = _ALPHA_RADIUS,
    dtype: str = _DTYPE,
    chunk: int = _CHUNK,
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

    if dtype not in ("float32", "float16"):
        raise TranslucencyError(f"--dtype: expected float32 or float16, got {dtype!r}")
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
        float16=dtype == "float16",
        overwrite=overwrite,
        scheduler=scheduler,
        max_memory=max_memory,
        reporter=RichReporter(quiet),
    )
    s = fitting.summary
    mesh_of = f", mesh of {len(fitting.model.alpha.values):,} vertices" if s["geometry"] == "mesh" else ""
    line = f"model: {fitting.path} ({s['seconds']:.1f} s, {s['rounds']} rounds{mesh_of})"
    chosen = [s["structure"]["summary"]] if s.get("structure") else []
    finish(as_json, quiet, s, [*chosen, line])
