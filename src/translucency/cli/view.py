"""``translucency view``: a fitted model in the browser — served live from this machine (point, spot,
directional and environment lights, maps, profiles), or written as a static page (``--export DIR``) that
opens from disk with no Python and no server (directional and environment lights by precomputed
radiance transfer)."""

from __future__ import annotations

import time
import webbrowser
from pathlib import Path

import typer

from .._validate import TranslucencyError, check_option
from ..io.inputs import expect_input
from ..io.model_file import load_model, read_header
from ._common import finish, info, json_option, overwrite_option, quiet_option, user_errors

#: the page's budget: the pig's page must stay below it (issue 26)
PAGE_BUDGET_MB = 20.0


@user_errors
def view(
    model: Path = typer.Argument(..., help="A per-vertex model file (translucency fit on a mesh data set)."),
    export: Path = typer.Option(
        None,
        "--export",
        help="Write a static page into this folder (index.html, viewer.js, data.js) instead of serving: it "
        "opens from disk in any browser, relit under a directional or environment light you turn.",
    ),
    port: int = typer.Option(8080, "--port", help="Serve on this port (another is taken if it is in use)."),
    open_browser: bool = typer.Option(
        True, "--browser/--no-browser", help="Open the page in the default browser (else print the address)."
    ),
    sky: str = typer.Option(
        None,
        "--sky",
        metavar="ENV",
        help="The environment light: env:L (a constant sky, W/(mm^2 sr)) or env:MAP.exr[,scale] (as render's "
        "--light); default a constant sky giving 1/3 of the directional light's irradiance.",
    ),
    bands: int = typer.Option(
        4,
        "--bands",
        help="Bands of the light basis (spherical harmonics): bands^2 "
        "coefficients per vertex and channel; 2 to 5.",
    ),
    radius: float = typer.Option(
        None,
        "--radius",
        help="Near radius of the transport, mm (default as render's: the 99% energy radius).",
    ),
    seconds: float = typer.Option(
        0.0, "--seconds", help="Serve this long, then stop (0: until Ctrl-C).", hidden=True
    ),
    overwrite: bool = overwrite_option(),
    quiet: bool = quiet_option(),
    as_json: bool = json_option(),
):
    """Look at a fitted model in the browser: relight it, read its maps and profiles, or write a static page."""  # noqa: E501 — Typer lists the docstring verbatim as the one-line help
    from ..render.lights import EnvironmentLight, parse_light  # numpy only

    check_option("--bands", bands, lo=2, hi=5)
    check_option("--radius", radius, lo=1e-6, hi=1e9)
    check_option("--port", port, lo=0, hi=65535)
    environment = None
    if sky is not None:
        environment = parse_light(sky)
        if not isinstance(environment, EnvironmentLight):
            raise TranslucencyError(f"--sky {sky}: an environment light, env:L or env:MAP.exr[,scale]")
    expect_input(model, ("model file",))
    m = load_model(model)
    header = read_header(model)
    if m.geometry != "mesh":
        raise TranslucencyError(
            f"{model}: a planar model; view takes a per-vertex model of a mesh data set "
            "(a planar model's maps and profiles: translucency evaluate)"
        )
    if export is not None:
        return _export(m, header, model, export, environment, bands, radius, overwrite, quiet, as_json)
    return _serve(m, header, model, port, open_browser, environment, bands, radius, seconds, quiet, as_json)


def _prepare_args(m, header, model: Path):
    """(mesh, η, data set or None) of a model: its mesh, its boundary, its data set if still at hand."""
    from ..io.mesh_dataset import is_mesh_dataset, open_mesh_dataset
    from ..render import boundary_eta, object_of_model

    mesh, acquisition = object_of_model(m, header)
    dataset = header.get("meta", {}).get("dataset") or ""
    ds = open_mesh_dataset(dataset) if dataset and is_mesh_dataset(dataset) else None
    if ds is not None and int(ds.n_points) != m.n_points:
        ds = None  # another acquisition than the one fitted: no measured rings
    return mesh, boundary_eta(acquisition), ds


def _export(m, header, model: Path, out: Path, environment, bands, radius, overwrite, quiet, as_json):
    from ..io.outputs import claim_folder
    from ..view.object_page import prepare_object
    from ..view.page import write_page

    claim_folder(out, overwrite=overwrite, inputs=[model], option="--export")
    mesh, eta, ds = _prepare_args(m, header, model)
    t = time.perf_counter()
    view = prepare_object(
        m,
        mesh,
        eta=eta,
        environment=environment,
        bands=bands,
        radius=radius,
        dataset=ds,
        name=model.name.removesuffix(".model.zip"),
        progress=lambda step: info(quiet, f"{step}…"),
    )
    meta, arrays = view.page_data()
    sizes = write_page(out, meta, arrays)
    total_mb = sum(sizes.values()) / 1e6
    summary = {
        "command": "view",
        "model": model,
        "page": out / "index.html",
        "vertices": len(mesh.vertices),
        "bands": bands,
        "page_mb": total_mb,
        "error_vs_render": view.errors,
        "seconds": time.perf_counter() - t,
        **{f"{k}_s": v for k, v in view.seconds.items()},
    }
    lines = [
        f"page: {out / 'index.html'} ({total_mb:.1f} MB; open it in a browser, no server needed)",
        "relative RMSE against render for the same light: "
        + ", ".join(f"{k} {v:.3f}" for k, v in view.errors.items()),
    ]
    if total_mb > PAGE_BUDGET_MB:
        lines.append(f"note: the page is over {PAGE_BUDGET_MB:g} MB; --bands 3 makes it smaller")
    finish(as_json, quiet, summary, lines)


def _serve(m, header, model: Path, port, open_browser, environment, bands, radius, seconds, quiet, as_json):
    from ..view.object_page import prepare_object, surface_data
    from ..view.server import ViewServer

    mesh, eta, ds = _prepare_args(m, header, model)
    name = model.name.removesuffix(".model.zip")
    surface = surface_data(m, mesh, name=name, dataset=ds)

    def prepare(say):
        return prepare_object(
            m,
            mesh,
            eta=eta,
            environment=environment,
            bands=bands,
            radius=radius,
            dataset=ds,
            name=name,
            check_error=False,
            progress=say,
        )

    try:
        server = ViewServer(surface, prepare, port=port)
    except OSError as exc:
        raise TranslucencyError(f"--port {port}: cannot serve there ({exc.strerror})") from None
    if server.port_note:
        info(quiet, server.port_note)
    server.start()
    opened = open_browser and _open(server.url)
    info(quiet, f"viewer: {server.url}" + ("" if opened else "  (no browser opened: open this address)"))
    info(quiet, "the maps first; the relighting follows once the transport is prepared. Ctrl-C stops.")
    try:
        start = time.monotonic()
        while not seconds or time.monotonic() - start < seconds:
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
    finish(
        as_json,
        True,
        {"command": "view", "model": model, "url": server.url, "ready": server.view is not None},
    )


def _open(url: str) -> bool:
    """Open ``url`` in the default browser; False where there is none."""
    try:
        return bool(webbrowser.open(url))
    except webbrowser.Error:
        return False
