"""Rendering one fitted object as one function: relit under a light (:func:`render_model`), with the
path-traced reference and their comparison on request.

``translucency render`` is this function: the arguments checked at the boundary, the model and the
light placed, the object prepared (:class:`~translucency.transport.PreparedObject`: its transport, the near
radius chosen once), the memory and time estimated before the work (refused in one line beyond
``max_memory``), the pictures (EXR linear, PNG tone-mapped) and the numbers.  Units: mm, radiance in
W/(mm² sr), linear RGB.  A user's Mitsuba scene: :mod:`.scene_rendering`.
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
from pathlib import Path

import numpy as np

from .. import resources
from .._validate import TranslucencyError, check_option
from ..io.inputs import expect_input
from ..io.vertex_model import check_vertex_model
from ..model.lean import NO_LEAN, has_lean
from ..render import Camera, parse_light
from ..render.camera import view_direction
from ..render.compare import FLIP_SKIPPED, flip_available
from ..render.lights import DEFAULT_LIGHT, Placement, place_light
from ..render.object import boundary_eta, check_light_outside, object_of_model, volume_of_dataset
from ..render.reference import check_reference
from ..render.still import render_still
from ..render.tonemap import parse_exposure
from ..resources.run import Reporter, Run
from ..rig.shared.hdr import read_hdr
from ..transport import PreparedObject, TransportOptions
from ._arguments import model_and_record, whole_number

__all__ = ["DEFAULT_LIGHT", "Rendering", "render_model"]


@dataclasses.dataclass
class Rendering:
    """What :func:`render_model` made: our picture, the reference (if asked for), the numbers, the folder.

    Examples
    --------
    The example model the package ships, drawn small; no folder given, so none is kept:

    >>> import translucency as tl
    >>> shot = tl.render_model(tl.data.example_path("spot_coarse.model.zip"), resolution=(64, 48))
    >>> shot.picture.shape, shot.reference is None, shot.folder is None
    ((48, 64, 3), True, True)
    >>> bool(shot.picture.max() > 0), shot.summary["command"]
    (True, 'render')
    """

    picture: np.ndarray  # (H, W, 3) linear radiance, our model's
    reference: np.ndarray | None  # (H, W, 3) Mitsuba volpath of the filling, or None
    numbers: dict  # render.json: timings, and with a reference FLIP, relative RMSE, regions
    folder: Path | None  # where ours.exr/.png (and the reference, render.png) are; None: not kept
    summary: dict = dataclasses.field(default_factory=dict)  # ``translucency render --json``


def render_model(
    model, out=None, *, light=DEFAULT_LIGHT, view=(1.0, -1.6, 0.7), resolution=(320, 240),
    exposure: str = "fixed", reference: bool = False, spp: int = 32, radius: float | None = None,
    paper: bool = False, angles: bool = False, transport: TransportOptions | str | None = None,
    overwrite: bool = False, max_memory: str | int | None = None, reporter: Reporter | None = None,
) -> Rendering:  # fmt: skip
    """Relight a fitted object under a light: its prepared transport drawn through a Mitsuba camera.

    ``translucency render MODEL`` is this function.

    Parameters
    ----------
    model : FitResult, ReflectanceModel or path
        A per-vertex model (a fit on a mesh data set) that carries its mesh.
    out : str or Path, optional
        Folder for ``ours.exr/.png`` (and ``reference.exr/.png``, ``render.png``, ``render.json``);
        default: none kept, the pictures are only returned.
    light : str or Light
        In the object's frame, mm: ``point:x,y,z[,I]``, ``directional:dx,dy,dz[,E]``, ``spot:…``,
        ``env:L``, ``env:MAP.exr``, or relative to the object ``point@AZ,EL[,DIST[,I]]``, …
        (:func:`translucency.render.parse_light`), or a light object.
    view : (float, float, float) or str
        Direction from the object's centre towards the camera (the camera looks at the centre from 1.9
        object sizes).
    resolution : (int, int)
        Width and height in pixels.
    exposure : str
        Of the PNGs: ``fixed``, ``fixed+STOPS``, ``auto`` or a factor on the linear radiance (the EXRs are
        linear whatever the exposure).
    reference : bool
        Also path-trace the reference (Mitsuba volpath of the filling) and compare.
    spp : int
        Samples per pixel of each of the reference's two renders.
    radius : float, optional
        Near radius of the transport, mm (default: the 99 % energy radius, or less where the pairs
        would not fit in a quarter of ``max_memory`` or of the machine's memory).
    paper : bool
        Draw the paper's model: each point's radial profile alone.  By default the model's through-body
        table (:mod:`translucency.model.through`) is drawn with it wherever the model holds one (every fit
        on a mesh); the summary's ``through`` says whether it was.
    angles : bool
        Lean the near transport toward the light's and the camera's directions (a model fitted from a
        data set with oblique beams, :mod:`translucency.model.lean`; a light of one direction per vertex);
        the summary's ``angles`` says whether it did.
    transport : TransportOptions or str, optional
        The transport's choices as one object (:class:`translucency.transport.TransportOptions`: a variant
        registered by name, an experimental incidence law), or a kind's name (``"walked"``: the light that
        crosses the body walked through the medium estimated from the scan,
        :mod:`translucency.transport.walk`); ``radius``, ``paper`` and ``angles`` are laid over it.
    overwrite : bool
        Replace an earlier output folder of translucency at ``out`` (never anything else).
    max_memory : str or int, optional
        Most memory the render may use; a larger estimate is refused before any work.
    reporter : Reporter, optional
        Hears the run's information lines and progress (default: silent).

    Returns
    -------
    Rendering
        ``.picture``, ``.reference``, ``.numbers`` (render.json), ``.folder``, ``.summary``.

    Examples
    --------
    The example model under a light from the upper left, its pictures kept in a folder:

    >>> import tempfile
    >>> from pathlib import Path
    >>> import translucency as tl
    >>> out = Path(tempfile.mkdtemp()) / "render"
    >>> shot = tl.render_model(tl.data.example_path("spot_coarse.model.zip"), out, light="point@-45,40",
    ...                        resolution=(64, 48))
    >>> shot.picture.shape, sorted(p.name for p in out.glob("ours.*"))
    ((48, 64, 3), ['ours.exr', 'ours.png'])

    With ``reference=True`` Mitsuba's volpath path-traces the filling too and ``shot.numbers`` holds
    their relative RMSE (tens of seconds for this object at ``spp=4``).
    """
    # the arguments first (no file read), then the model and what it implies, then the output, then work
    check_option("spp", whole_number("spp", spp), lo=1)
    size = _resolution(resolution)
    chosen_exposure = parse_exposure(exposure, name="exposure")
    relative = parse_light(light) if isinstance(light, str) else light  # placed once the object is known
    if not hasattr(relative, "place"):  # a light, or one placed relative to the object
        raise TranslucencyError(f"light: expected a light or its text (point:x,y,z,I …), got {light!r}")
    options = TransportOptions.of(transport, paper=paper, angles=angles, radius=radius)
    run = Run("render", max_memory=max_memory, reporter=reporter)
    direction = view_direction(view, "view")
    fitted, record, mesh, acquisition = _object(model)
    placement = Placement.of(mesh, direction)
    lit, eta, volume = _lit(mesh, acquisition, relative, placement, reference)
    budget = resources.memory.transport_budget(run.limit)  # the pairs within a share of the memory
    options = TransportOptions.of(options, max_pairs=min(options.max_pairs, 2 * budget))
    prepared = PreparedObject(fitted, mesh, eta=eta, options=options)  # the near radius chosen once
    picture = dict(vertices=len(mesh.vertices), surface_mm2=float(mesh.area), radius_mm=prepared.radius,
                   width=size[0], height=size[1], reference=reference, spp_reference=spp,
                   max_pairs=options.max_pairs)  # fmt: skip
    inputs = [model, record.get("dataset") or None] if isinstance(model, (str, os.PathLike)) else []
    with tempfile.TemporaryDirectory(prefix="translucency-render-") as scratch:
        folder = Path(scratch) if out is None else Path(out)
        need = run.check(resources.memory.rendering(**picture), None if out is None else folder)
        if out is not None:
            run.claim_folder(folder, overwrite=overwrite, inputs=inputs)
        _announce(run, need, picture, placement, lit, prepared, reference)
        camera = Camera.looking_at(mesh, direction, *size)
        numbers = _drawn(run, prepared, lit, folder, volume, camera, spp, chosen_exposure)
        ours = read_hdr(folder / "ours.exr")
        ref = read_hdr(folder / "reference.exr") if reference else None
    summary = {"command": "render", "model": model, "images": out, **numbers, "light": lit.record()}
    return Rendering(ours, ref, numbers, None if out is None else folder, run.summary(summary))


def _lit(mesh, acquisition: dict, relative, placement, reference: bool):
    """(the light placed in the object's frame, the boundary's η, the filling for the reference or None):
    one line, before any work, for a light inside the object, one volpath cannot render, a filling gone."""
    lit = place_light(relative, placement)
    check_light_outside(mesh, lit)
    eta = boundary_eta(acquisition)
    if reference:  # a light volpath cannot render, a filling gone or changed: one line, before any work
        check_reference(lit, eta)
    return lit, eta, volume_of_dataset(mesh, acquisition) if reference else None


def _drawn(run, prepared, lit, folder: Path, volume, camera, spp: int, exposure) -> dict:
    """The still drawn into ``folder`` (and with ``volume`` its reference and their comparison), each step
    told to the run's progress; returns its numbers (render.json)."""
    steps = 3 if volume is None else 4
    with run.work("render", total=steps) as work:
        numbers = render_still(
            prepared, lit, folder, volume=volume, camera=camera, spp_reference=spp, exposure=exposure,
            progress=work.step(),
        )  # fmt: skip
        work.update(completed=steps, item="done")
        work.fresh = not numbers.get("reference_cached", False)
    return numbers


def _resolution(resolution) -> tuple[int, int]:
    """(width, height) in pixels, each a whole number from 1 to 16384, or one line naming the argument."""
    size = tuple(whole_number("resolution", v) for v in np.atleast_1d(resolution))
    if len(size) != 2:
        raise TranslucencyError(f"resolution: expected (width, height), got {resolution!r}")
    for v in size:
        check_option("resolution", v, hi=16384)
    return size


def _object(model):
    """(the loaded per-vertex model, its file's record, its mesh, its acquisition header): one line for a
    file that is not a per-vertex model."""
    if isinstance(model, (str, os.PathLike)):
        expect_input(Path(model), ("model file",))  # a data set or a mesh file where the model belongs
    fitted, record = model_and_record("model", model)
    check_vertex_model(fitted, "render", model if isinstance(model, (str, os.PathLike)) else "model")
    mesh, acquisition = object_of_model(fitted, {"meta": record})
    return fitted, record, mesh, acquisition


def _announce(run, need, picture: dict, placement, lit, prepared, reference: bool) -> None:
    """The render's information lines: its size, time and memory; where the object and the light are; what
    is drawn instead of what was asked (no FLIP, no lean)."""
    timing = run.time(resources.timing.rendering_units(**picture))
    what, _, flags = need.what.partition(": ")  # "the transport: --radius"
    run.info(
        f"render of {picture['vertices']:,} vertices at {picture['width']} x {picture['height']}, transport "
        f"radius {prepared.radius:.3g} mm; time {timing.text()}, memory ~{need.memory / 2**30:.2g} GiB "
        f"(mostly {what}{f'; a smaller {flags} lowers it' if flags else ''})"
    )
    run.info(f"{placement.describe()}; light {lit!r}")
    if reference and not flip_available():  # the comparison goes on with the relative RMSE
        run.info(FLIP_SKIPPED)
    if prepared.options.angles and not has_lean(prepared.model):  # one line: what is drawn instead
        run.info(NO_LEAN)
    elif prepared.options.angles and not lit.delta:
        run.info("--angles: a light of many directions leans by its irradiance-weighted mean direction")
