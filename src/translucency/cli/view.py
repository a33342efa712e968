"""``translucency view``: a fitted model in the browser — served live from this machine (point, spot,
directional and environment lights, maps, profiles), or written as a static page (``--export DIR``) that
opens from disk with no Python and no server (directional and environment lights by precomputed
radiance transfer): :func:`translucency.workflow.viewing.view_model`."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import (
    PANEL_COMPARISON,
    PANEL_LIGHT,
    PANEL_RUN,
    PANEL_TRANSPORT,
    finish,
    json_option,
    max_memory_option,
    overwrite_option,
    quiet_option,
    user_errors,
)
from ._run import RichReporter

#: the options with long help, named here so that the command reads as its calls
_EXPORT = typer.Option(
    None,
    "--export",
    help="Write a static page into this folder (index.html, viewer.js, data.js) instead of serving: it "
    "opens from disk in any browser, relit under a directional or environment light you turn.",
)
_SKY = typer.Option(
    None,
    "--sky",
    metavar="ENV",
    help="The environment light: env:L (a constant sky, W/(mm^2 sr)) or env:MAP.exr[,scale] (as render's "
    "--light); default a constant sky giving 1/3 of the directional light's irradiance.",
    rich_help_panel=PANEL_LIGHT,
)
_BANDS = typer.Option(
    4,
    "--bands",
    help="Bands of the light basis (spherical harmonics): bands^2 "
    "coefficients per vertex and channel; 2 to 5.",
    rich_help_panel=PANEL_TRANSPORT,
)
_COMPARE = typer.Option(
    None,
    "--compare",
    help="A second per-vertex model of the same mesh (another fit, another family): shown beside the "
    "first and as their difference |B - A| / A under the same directional or environment light.",
    rich_help_panel=PANEL_COMPARISON,
)
_REFERENCE_RENDER = typer.Option(
    None,
    "--reference-render",
    help="A render folder with its path-traced reference (translucency render --reference, or the "
    "demo's results/report): its error map (FLIP) and numbers beside the model.",
    rich_help_panel=PANEL_COMPARISON,
)
_TRUTH = typer.Option(
    None,
    "--truth",
    help="A planar model's independent acquisition (another seed of the same points): its ring means "
    "beside the data's in each point's profile.",
    rich_help_panel=PANEL_COMPARISON,
)
_RADIUS = typer.Option(
    None,
    "--radius",
    help="Near radius of the transport, mm (default as render's: the 99% energy radius).",
    rich_help_panel=PANEL_TRANSPORT,
)

_ANGLES = typer.Option(
    False,
    "--angles",
    help="Draw the model's lean (fitted from a data set acquired with --incidence): every "
    "light and sky leans the transport toward the directions it arrives from, as render --angles. The "
    "transfer takes one relight per direction of its lattice (256): slower to prepare.",
    rich_help_panel=PANEL_TRANSPORT,
)


@user_errors
def view(
    model: Path = typer.Argument(
        ..., help="A model file: per-vertex (fit on a mesh data set) or planar (fit on a planar data set)."
    ),
    export: Path = _EXPORT,
    port: int = typer.Option(8080, "--port", help="Serve on this port (another is taken if it is in use)."),
    open_browser: bool = typer.Option(
        True, "--browser/--no-browser", help="Open the page in the default browser (else print the address)."
    ),
    sky: str = _SKY,
    bands: int = _BANDS,
    compare: Path = _COMPARE,
    reference_render: Path = _REFERENCE_RENDER,
    truth: Path = _TRUTH,
    radius: float = _RADIUS,
    angles: bool = _ANGLES,
    seconds: float = typer.Option(
        0.0,
        "--seconds",
        help="Serve this long, then stop (0: until Ctrl-C; for scripts and tests).",
        rich_help_panel=PANEL_RUN,
    ),
    overwrite: bool = overwrite_option(),
    max_memory: str = max_memory_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Look at a fitted model in the browser: relight it, read its maps and profiles, or write a static page."""  # noqa: E501 — Typer lists the docstring verbatim as the one-line help
    from ..workflow.viewing import PAGE_BUDGET_MB, view_model  # heavy: the render stage loads only to view

    summary = view_model(
        model,
        export,
        port=port,
        open_browser=open_browser,
        sky=sky,
        bands=bands,
        compare=compare,
        reference_render=reference_render,
        truth=truth,
        radius=radius,
        angles=angles,
        seconds=seconds,
        overwrite=overwrite,
        max_memory=max_memory,
        reporter=RichReporter(quiet),
    )
    if export is None:  # served: the address was said while serving
        finish(as_json, True, summary)
        return
    finish(as_json, quiet, summary, _page_lines(summary, PAGE_BUDGET_MB))


def _page_lines(summary: dict, budget_mb: float) -> list[str]:
    """Where the page is and how large, the relighting's error against render, a note over ``budget_mb``."""
    total_mb = summary["page_mb"]
    lines = [f"page: {summary['page']} ({total_mb:.1f} MB; open it in a browser, no server needed)"]
    if "error_vs_render" in summary:
        errors = ", ".join(f"{k} {v:.3f}" for k, v in summary["error_vs_render"].items())
        lines.append(f"relative RMSE against render for the same light: {errors}")
    if total_mb > budget_mb:
        lines.append(f"note: the page is over {budget_mb:g} MB; --bands 3 makes it smaller")
    return lines
