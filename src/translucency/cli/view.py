"""``translucency view``: a fitted model in the browser — served live from this machine (point, spot,
directional and environment lights, maps, profiles), or written as a static page (``--export DIR``) that
opens from disk with no Python and no server (directional and environment lights by precomputed
radiance transfer)."""

from __future__ import annotations

import base64
import json
import time
import webbrowser
from pathlib import Path

import numpy as np
import typer

from .._validate import TranslucencyError, check_option
from ..io.dataset import open_dataset
from ..io.inputs import expect_input
from ..io.mesh_dataset import is_mesh_dataset, open_mesh_dataset
from ..io.model_file import load_model, read_header
from ..io.outputs import claim_folder, kind_of
from ..view.page import write_page
from ._common import finish, info, json_option, overwrite_option, quiet_option, user_errors

#: the page's budget: the pig's page must stay below it (issue 26)
PAGE_BUDGET_MB = 20.0


@user_errors
def view(
    model: Path = typer.Argument(
        ..., help="A model file: per-vertex (fit on a mesh data set) or planar (fit on a planar data set)."
    ),
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
    compare: Path = typer.Option(
        None,
        "--compare",
        help="A second per-vertex model of the same mesh (another fit, another family): shown beside the "
        "first and as their difference |B - A| / A under the same directional or environment light.",
    ),
    reference: Path = typer.Option(
        None,
        "--reference",
        help="A render folder with its path-traced reference (translucency render --reference, or the main "
        "job's results/report): its error map (FLIP) and numbers beside the model.",
    ),
    truth: Path = typer.Option(
        None,
        "--truth",
        help="A planar model's independent acquisition (another seed of the same points): its ring means "
        "beside the data's in each point's profile.",
    ),
    radius: float = typer.Option(
        None,
        "--radius",
        help="Near radius of the transport, mm (default as render's: the 99% energy radius).",
    ),
    seconds: float = typer.Option(
        0.0, "--seconds", help="Serve this long, then stop (0: until Ctrl-C; for scripts and tests)."
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
        if environment.kind != EnvironmentLight.kind:
            raise TranslucencyError(f"--sky {sky}: an environment light, env:L or env:MAP.exr[,scale]")
    expect_input(model, ("model file",))
    m = load_model(model)
    header = read_header(model)
    if m.geometry != "mesh":
        meta, arrays = _planar(m, header, model, truth, bands)
        if export is not None:
            claim_folder(export, overwrite=overwrite, inputs=[model, truth], option="--export")
            return _write(export, meta, arrays, {"model": model}, [], quiet, as_json)
        return _serve_until(_server((meta, arrays), None, port), model, open_browser, seconds, quiet, as_json)
    if truth is not None:
        raise TranslucencyError("--truth: for a planar model (a mesh model's profiles show its own data)")
    other = _companion(compare, m) if compare is not None else None
    figure = _reference_figure(reference) if reference is not None else None
    if export is not None:  # claimed before any work
        claim_folder(export, overwrite=overwrite, inputs=[model], option="--export")
    from ..render import boundary_eta, object_of_model  # heavy: trimesh, Mitsuba, Numba load only to view
    from ..view.object_page import prepare_object, surface_data  # heavy: the render stage

    mesh, acquisition = object_of_model(m, header)
    ds = _mesh_dataset(m, header)
    options = dict(eta=boundary_eta(acquisition), environment=environment, bands=bands, radius=radius)

    def prepare(say, check_error: bool):
        """The model's view (and ``--compare``'s beside it): the transport and the transfer."""
        view = prepare_object(
            m, mesh, **options, dataset=ds, name=_name(model), check_error=check_error, progress=say
        )
        if other is not None:
            say(f"{compare.name}: the second model")
            view.companion = prepare_object(
                other, mesh, **options, name=_name(compare), check_error=False, progress=say
            )
        return view

    if export is None:
        surface = surface_data(m, mesh, name=_name(model), dataset=ds)
        if figure is not None:
            surface[0]["reference"] = figure
        info(quiet, "the maps first; the relighting follows once the transport is prepared.")
        server = _server(surface, lambda say: prepare(say, False), port)
        return _serve_until(server, model, open_browser, seconds, quiet, as_json)
    t = time.perf_counter()
    view = prepare(lambda step: info(quiet, f"{step}…"), True)
    meta, arrays = view.page_data()
    if figure is not None:
        meta["reference"] = figure
    summary = {
        "model": model,
        "vertices": len(mesh.vertices),
        "bands": bands,
        "error_vs_render": view.errors,
        "seconds": time.perf_counter() - t,
        **{f"{k}_s": v for k, v in view.seconds.items()},
    }
    errors = ", ".join(f"{k} {v:.3f}" for k, v in view.errors.items())
    _write(
        export,
        meta,
        arrays,
        summary,
        [f"relative RMSE against render for the same light: {errors}"],
        quiet,
        as_json,
    )


def _name(model: Path) -> str:
    """A model's name on the page: its file's, less ``.model.zip``."""
    return model.name.removesuffix(".model.zip")


def _mesh_dataset(m, header):
    """The mesh data set a model was fitted to, if it is still at hand with the model's points (its measured
    ring means), else None."""
    dataset = header.get("meta", {}).get("dataset") or ""
    ds = open_mesh_dataset(dataset) if dataset and is_mesh_dataset(dataset) else None
    return ds if ds is not None and int(ds.n_points) == m.n_points else None


def _reference_figure(folder: Path) -> dict:
    """The error map of a render against its path-traced reference (``render.png``/``.json``, or the main
    job's ``figure2.png``/``.json``) for the page, or one line why the folder holds none."""
    for name in ("render", "figure2"):
        png, summary = folder / f"{name}.png", folder / f"{name}.json"
        if png.is_file() and summary.is_file():
            numbers = json.loads(summary.read_text())
            if "rel_rmse" not in numbers:
                break
            keep = ("rel_rmse", "flip_mean_object", "reference_noise", "reference_spp", "light")
            return {
                "png": base64.b64encode(png.read_bytes()).decode("ascii"),
                "file": str(png),
                **{k: numbers[k] for k in keep if k in numbers},
            }
    raise TranslucencyError(
        f"--reference {folder}: no render with a reference there (render.png and render.json from "
        "'translucency render --reference', or the main job's figure2.png and figure2.json)"
    )


def _companion(path: Path, m):
    """The ``--compare`` model: a per-vertex model on the first one's mesh, or one line why not."""
    expect_input(path, ("model file",), option="--compare")
    other = load_model(path)
    if other.geometry != "mesh":
        raise TranslucencyError(f"--compare {path}: a planar model; compare takes a per-vertex model")
    a, b = np.asarray(m.alpha.vertices), np.asarray(other.alpha.vertices)
    if a.shape != b.shape or not np.allclose(a, b, atol=1e-6 * float(np.ptp(a, axis=0).max())):
        raise TranslucencyError(
            f"--compare {path}: another mesh ({len(b):,} vertices against {len(a):,}); compare needs the same"
        )
    return other


def _planar(m, header, model: Path, truth, bands):
    """(meta, arrays) of a planar sample's page, all of it at once."""
    from ..view.planar_page import planar_page_data  # heavy: the render stage's light basis (trimesh)

    dataset = header.get("meta", {}).get("dataset") or ""
    ds = open_dataset(dataset) if dataset and kind_of(dataset) == "planar data set" else None
    if ds is not None and ds.n_points != m.n_points:
        ds = None  # another acquisition than the one fitted: no measured rings
    true = None
    if truth is not None:
        expect_input(truth, ("planar data set",), option="--truth")
        true = open_dataset(truth)
        if true.n_points != m.n_points or (ds is not None and tuple(true.window) != tuple(ds.window)):
            raise TranslucencyError(f"--truth {truth}: {true.n_points} points, the model has {m.n_points}")
    return planar_page_data(m, name=_name(model), dataset=ds, truth=true, bands=bands)


def _write(
    out: Path, meta: dict, arrays: dict, summary: dict, lines: list, quiet: bool, as_json: bool
) -> None:
    """Write the page into ``out`` (claimed) and say where, how large, and ``lines``."""
    total_mb = sum(write_page(out, meta, arrays).values()) / 1e6
    summary = {"command": "view", **summary, "page": out / "index.html", "page_mb": total_mb}
    lines = [
        f"page: {out / 'index.html'} ({total_mb:.1f} MB; open it in a browser, no server needed)",
        *lines,
    ]
    if total_mb > PAGE_BUDGET_MB:
        lines.append(f"note: the page is over {PAGE_BUDGET_MB:g} MB; --bands 3 makes it smaller")
    finish(as_json, quiet, summary, lines)


def _server(surface, prepare, port: int):
    """The live viewer's server on ``port`` (or another, said), or one line why it cannot serve."""
    from ..view.server import ViewServer  # the server (and its page) only where one is started

    try:
        return ViewServer(surface, prepare, port=port)
    except OSError as exc:
        raise TranslucencyError(f"--port {port}: cannot serve there ({exc.strerror})") from None


def _serve_until(server, model: Path, open_browser: bool, seconds: float, quiet: bool, as_json: bool) -> None:
    """Serve, say where, open a browser (or say there is none), stop after ``seconds`` or at Ctrl-C."""
    if server.port_note:
        info(quiet, server.port_note)
    server.start()
    opened = open_browser and _open(server.url)
    info(quiet, f"viewer: {server.url}" + ("" if opened else "  (no browser opened: open this address)"))
    info(quiet, "Ctrl-C stops.")
    try:
        start = time.monotonic()
        while not seconds or time.monotonic() - start < seconds:
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
    finish(as_json, True, {"command": "view", "model": model, "url": server.url})


def _open(url: str) -> bool:
    """Open ``url`` in the default browser; False where there is none."""
    try:
        return bool(webbrowser.open(url))
    except webbrowser.Error:
        return False
