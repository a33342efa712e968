"""Viewing as one function: a fitted model in the browser, served live from this machine (point, spot,
directional and environment lights, maps, profiles), or written as a static page that opens from disk
with no Python and no server (directional and environment lights by precomputed radiance transfer).

:func:`view_model` is ``translucency view``: the options checked, the model read, and either the page
written (``export``) or the live viewer served until ``seconds`` have passed or Ctrl-C.  Units: mm,
radiance in W/(mm² sr), linear RGB.
"""

from __future__ import annotations

import base64
import json
import time
import webbrowser
from pathlib import Path

import numpy as np

from .. import resources
from .._validate import TranslucencyError, check_option
from ..io.dataset import open_dataset
from ..io.inputs import expect_input
from ..io.mesh_dataset import is_mesh_dataset, open_mesh_dataset
from ..io.model_file import load_model, read_header
from ..io.outputs import claim_folder, kind_of
from ..model.lean import NO_LEAN, has_lean
from ..resources.memory import transport_pairs
from ..resources.run import Reporter, Run, Silent
from ..view.page import write_page
from ..view.surface import check_reduced_mesh

__all__ = ["PAGE_BUDGET_MB", "view_model"]

#: the page's budget: the pig's page must stay below it (issue 26)
PAGE_BUDGET_MB = 20.0


def view_model(
    model,
    export=None,
    *,
    port: int = 8080,
    open_browser: bool = True,
    sky: str | None = None,
    bands: int = 4,
    compare=None,
    reference_render=None,
    truth=None,
    radius: float | None = None,
    angles: bool = False,
    transport=None,
    seconds: float = 0.0,
    overwrite: bool = False,
    max_memory: str | int | None = None,
    reporter: Reporter | None = None,
) -> dict:
    """Look at a fitted model in the browser: relight it, read its maps and profiles, or write a static page.

    ``translucency view MODEL`` is this function.  Without ``export`` it serves the live viewer on
    ``port`` (another if that one is in use), opens a browser (``open_browser``) and returns when
    ``seconds`` have passed (0: at Ctrl-C); with ``export`` it writes the static page there and returns.

    Parameters
    ----------
    model : str or Path
        A model file: per-vertex (a fit on a mesh data set) or planar.
    export : str or Path, optional
        Write a static page into this folder (``index.html``, ``viewer.js``, ``data.js``) instead of
        serving: it opens from disk in any browser, relit under a directional or environment light.
    port : int
        Serve on this port (0-65535; another is taken if it is in use).
    open_browser : bool
        Open the page in the default browser (else the address is told to ``reporter``).
    sky : str, optional
        The environment light: ``env:L`` (a constant sky, W/(mm² sr)) or ``env:MAP.exr[,scale]``; default
        a constant sky giving 1/3 of the directional light's irradiance.
    bands : int
        Bands of the light basis (spherical harmonics, 2 to 5): bands² coefficients per vertex and channel.
    compare : str or Path, optional
        A second per-vertex model of the same mesh: shown beside the first and as their difference.
    reference_render : str or Path, optional
        A render folder with its path-traced reference (``render_model(..., reference=True)``, or the main
        job's ``results/report``): its error map (FLIP) and numbers beside the model.
    truth : str or Path, optional
        A planar model's independent acquisition (another seed of the same points): its ring means beside
        the data's in each point's profile.
    radius : float, optional
        Near radius of the transport, mm (default as :func:`render_model`'s: the 99 % energy radius).
    angles : bool
        With a model that has a lean (fitted from a data set acquired with ``incidence``): the page draws
        it, every light and sky leaning the transport toward the directions it arrives from (the transfer
        takes one tilted relight per direction of its lattice: :mod:`translucency.transport.transfer`).
    transport : TransportOptions, optional
        The transport's choices as one object (:class:`translucency.transport.TransportOptions`, e.g. a
        variant registered by name); ``radius`` and ``angles`` are laid over it.
    seconds : float
        Serve this long, then stop (0: until Ctrl-C).
    overwrite : bool
        Replace an earlier page of translucency at ``export`` (never anything else).
    max_memory : str or int, optional
        Most memory the viewer may use; a larger estimate (a per-vertex model's transport and transfer) is
        refused before any work.
    reporter : Reporter, optional
        Hears the information lines: the steps, the address (default: silent).

    Returns
    -------
    dict
        The summary of ``translucency view --json``: with ``export`` the ``page``, its size ``page_mb``
        and for a per-vertex model the relighting's ``error_vs_render``; served, the ``url``.

    Raises
    ------
    TranslucencyError
        A bad option (named), not a model file, a ``compare`` model of another mesh, a folder without a
        render and its reference, a port that cannot serve.

    Examples
    --------
    The example model's page written into a folder (with ``export=None`` it is served instead):

    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> from translucency.workflow.viewing import PAGE_BUDGET_MB
    >>> page = tl.view_model(tl.data.example_path("spot_coarse.model.zip"), Path(tempfile.mkdtemp()) / "page")
    >>> page["page"].name, page["page_mb"] < PAGE_BUDGET_MB
    ('index.html', True)
    """
    reporter = reporter or Silent()
    environment = _check_options(sky, bands, radius, port)
    run = Run("view", max_memory=max_memory, reporter=reporter)  # (a bad size: one line, before any work)
    model = Path(model)
    expect_input(model, ("model file",))
    m = load_model(model)
    header = read_header(model)
    export = None if export is None else Path(export)
    serving = dict(port=port, open_browser=open_browser, seconds=seconds)
    if m.geometry != "mesh":
        meta, arrays = _planar(m, header, model, truth, bands)
        if export is not None:
            claim_folder(export, overwrite=overwrite, inputs=[model, truth], option="export")
            return run.summary(_write(export, meta, arrays, {"model": model}))
        return run.summary(_serve_until(_server((meta, arrays), None, port), model, serving, reporter))
    if truth is not None:
        raise TranslucencyError("truth: for a planar model (a mesh model's profiles show its own data)")
    check_reduced_mesh(len(m.faces))  # a large mesh without the viewer extra: one line, before any work
    from ..transport import TransportOptions  # heavy: Numba, SciPy load only for a mesh model

    other = _companion(Path(compare), m) if compare is not None else None
    lean = has_lean(m)
    options = TransportOptions.of(transport, angles=angles and lean, radius=radius)
    views = _ObjectViews(m, header, model, other, compare, environment, bands, options)
    run.check(_relighting_need(views, bands))
    views.figure = _reference_figure(Path(reference_render)) if reference_render is not None else None
    if export is not None:  # claimed before any work
        claim_folder(export, overwrite=overwrite, inputs=[model], option="export")
    if lean and not angles:  # one line: what is drawn
        reporter.info("the page draws the paper's model; --angles draws the model's lean")
    elif angles and not lean:
        reporter.info(NO_LEAN)
    if export is None:
        reporter.info("the maps first; the relighting follows once the transport is prepared.")
        server = _server(views.surface(), lambda say: views.prepare(say, False), port)
        return run.summary(_serve_until(server, model, serving, reporter))
    return run.summary(views.export(export, reporter))


def _relighting_need(views, bands: int):
    """A per-vertex model's relighting: its transport at the near radius its prepared object chose and its
    transfer of bands² coefficients (both twice with a second model to compare)."""
    mesh, objects = views.mesh, views.prepared
    pairs = sum(
        transport_pairs(
            vertices=len(mesh.vertices),
            surface_mm2=float(mesh.area),
            radius_mm=o.radius,
            max_pairs=o.options.max_pairs,
        )
        for o in objects
    )
    return resources.memory.relighting(
        vertices=len(mesh.vertices), faces=len(mesh.faces), pairs=pairs, coefficients=len(objects) * bands**2
    )


def _check_options(sky, bands: int, radius, port: int):
    """The options checked before any file is read; the environment light of ``sky`` (or None)."""
    from ..render.lights import EnvironmentLight, parse_light  # numpy only

    check_option("bands", bands, lo=2, hi=5)
    check_option("radius", radius, lo=1e-6, hi=1e9)
    check_option("port", port, lo=0, hi=65535)
    if sky is None:
        return None
    environment = parse_light(sky)
    if environment.kind != EnvironmentLight.kind:  # a relative light has a kind too
        raise TranslucencyError(f"sky {sky}: an environment light, env:L or env:MAP.exr[,scale]")
    return environment


class _ObjectViews:
    """A per-vertex model's view (and ``compare``'s beside it): its surface first, its prepared object's
    transport and transfer once built, or all of it written as a page."""

    def __init__(self, m, header, model: Path, other, compare, environment, bands, options):
        from ..render import boundary_eta, object_of_model  # heavy: trimesh, Mitsuba, Numba load only to view
        from ..transport import PreparedObject

        self.m, self.model, self.other, self.compare, self.figure = m, model, other, compare, None
        self.mesh, acquisition = object_of_model(m, header)
        self.ds = _mesh_dataset(m, header)
        self.bands, self.environment = bands, environment
        eta = boundary_eta(acquisition)
        #: the model's prepared object (and the second model's): the near radius chosen once, here
        self.prepared = [
            PreparedObject(x, self.mesh, eta=eta, options=options) for x in (m, other) if x is not None
        ]

    def surface(self):
        """What the live page shows at once: the mesh, the maps, the profiles (and the reference)."""
        from ..view.surface import surface_data  # heavy: the render stage

        surface = surface_data(self.m, self.mesh, name=_name(self.model), dataset=self.ds)
        if self.figure is not None:
            surface[0]["reference"] = self.figure
        return surface

    def prepare(self, say, check_error: bool):
        """The model's view (and ``compare``'s beside it): the transport and the transfer."""
        from ..view.object_page import viewed_object  # heavy: the render stage

        shown = dict(environment=self.environment, bands=self.bands, progress=say)
        view = viewed_object(
            self.prepared[0], dataset=self.ds, name=_name(self.model), check_error=check_error, **shown
        )
        if self.other is not None:
            say(f"{Path(self.compare).name}: the second model")
            view.companion = viewed_object(
                self.prepared[1], name=_name(Path(self.compare)), check_error=False, **shown
            )
        return view

    def export(self, out: Path, reporter) -> dict:
        """The static page written into ``out`` (claimed), with the relighting's error against render."""
        t = time.perf_counter()
        view = self.prepare(lambda step: reporter.info(f"{step}…"), True)
        meta, arrays = view.page_data()
        if self.figure is not None:
            meta["reference"] = self.figure
        summary = {
            "model": self.model,
            "vertices": len(self.mesh.vertices),
            "bands": self.bands,
            "angles": view.angles,
            "error_vs_render": view.errors,
            "seconds": time.perf_counter() - t,
            **{f"{k}_s": v for k, v in view.seconds.items()},
        }
        return _write(out, meta, arrays, summary)


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
        f"reference_render {folder}: no render with a reference there (render.png and render.json of a "
        "render with its path-traced reference, or the main job's figure2.png and figure2.json)"
    )


def _companion(path: Path, m):
    """The ``compare`` model: a per-vertex model on the first one's mesh, or one line why not."""
    expect_input(path, ("model file",), option="compare")
    other = load_model(path)
    if other.geometry != "mesh":
        raise TranslucencyError(f"compare {path}: a planar model; compare takes a per-vertex model")
    a, b = np.asarray(m.alpha.vertices), np.asarray(other.alpha.vertices)
    if a.shape != b.shape or not np.allclose(a, b, atol=1e-6 * float(np.ptp(a, axis=0).max())):
        raise TranslucencyError(
            f"compare {path}: another mesh ({len(b):,} vertices against {len(a):,}); compare needs the same"
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
        expect_input(truth, ("planar data set",), option="truth")
        true = open_dataset(truth)
        if true.n_points != m.n_points or (ds is not None and tuple(true.window) != tuple(ds.window)):
            raise TranslucencyError(f"truth {truth}: {true.n_points} points, the model has {m.n_points}")
    return planar_page_data(m, name=_name(model), dataset=ds, truth=true, bands=bands)


def _write(out: Path, meta: dict, arrays: dict, summary: dict) -> dict:
    """Write the page into ``out`` (claimed); the summary with where it is and how large."""
    total_mb = sum(write_page(out, meta, arrays).values()) / 1e6
    return {"command": "view", **summary, "page": out / "index.html", "page_mb": total_mb}


def _server(surface, prepare, port: int):
    """The live viewer's server on ``port`` (or another, said), or one line why it cannot serve."""
    from ..view.server import ViewServer  # the server (and its page) only where one is started

    try:
        return ViewServer(surface, prepare, port=port)
    except OSError as exc:
        raise TranslucencyError(f"port {port}: cannot serve there ({exc.strerror})") from None


def _serve_until(server, model: Path, serving: dict, reporter) -> dict:
    """Serve, say where, open a browser (or say there is none), stop after ``seconds`` or at Ctrl-C."""
    if server.port_note:
        reporter.info(server.port_note)
    server.start()
    opened = serving["open_browser"] and _open(server.url)
    reporter.info(f"viewer: {server.url}" + ("" if opened else "  (no browser opened: open this address)"))
    reporter.info("Ctrl-C stops.")
    seconds = serving["seconds"]
    try:
        start = time.monotonic()
        while not seconds or time.monotonic() - start < seconds:
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
    return {"command": "view", "model": model, "url": server.url}


def _open(url: str) -> bool:
    """Open ``url`` in the default browser; False where there is none."""
    try:
        return bool(webbrowser.open(url))
    except webbrowser.Error:
        return False
