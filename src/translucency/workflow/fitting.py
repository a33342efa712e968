"""Fitting as one function: a model per incident point, with the modulation texture α, to a data set.

:func:`fit_model` is ``translucency fit`` as a Python call: the arguments checked at the boundary, the
data set opened and checked once, the memory and time estimated before the work (refused in one line
beyond ``max_memory``), the fit (:func:`translucency.fit.fit_planar` or
:func:`translucency.fit.fit_mesh`, whichever the data set is), and with ``out`` the model file written
atomically with the fit's record.  Units: mm, R_d in mm⁻².
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import resources
from .._validate import TranslucencyError, check_option
from ..cluster import parse_scheduler
from ..fit import (
    FAMILIES,
    FIT_BLOCK,
    FitResult,
    check_fit_options,
    default_chunk_points,
    fit_mesh,
    fit_planar,
)
from ..fit.structure import resolve_structure
from ..io.dataset import PlanarDataset, dataset_identity
from ..io.datasets import open_any_dataset
from ..io.inputs import DATA_SETS, expect_input
from ..io.mesh_dataset import MeshDataset
from ..io.model_file import read_header, save_model
from ..io.outputs import claim_output
from ..model import check_physics
from ..resources.run import Reporter, Run
from ._arguments import refuse_unknown, whole_number

__all__ = ["Fitting", "fit_model"]

#: points of a mesh fit's chunk (as :func:`translucency.fit.fit_mesh` reads them; for the memory estimate)
MESH_FIT_CHUNK = 32


@dataclass
class Fitting:
    """What :func:`fit_model` made: the fit, the model file (if written) and the run's summary.

    Examples
    --------
    A window of one exponential, R_d = c e^{-s r} (c = 0.2 mm⁻², s = 2 mm⁻¹), fitted with one term: the
    fall-off comes back, and the total reflectance is the closed form 2π c / s² = 0.314:

    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np, translucency as tl
    >>> from translucency.io.dataset import write_dataset
    >>> x = (np.arange(33) - 16) * 0.25
    >>> R_d = np.repeat((0.2 * np.exp(-2.0 * np.hypot(*np.meshgrid(x, x))))[None, :, :, None], 3, axis=3)
    >>> data = write_dataset(Path(tempfile.mkdtemp()) / "d.zarr", [[0, 0]], [[-4.125, -4.125]], R_d, 0.25)
    >>> fitting = tl.fit_model(data, "iso", n_terms=1, max_rounds=1)
    >>> print(f"{fitting.model.d[0, 0, 0, 0]:.3f} {fitting.model.total_reflectance()[0, 0]:.3f}")
    -2.000 0.314
    >>> fitting.path is None, fitting.summary["n_points"]
    (True, 1)
    """

    result: FitResult  # .model (with its α), .flagged points, .history (Φ per round), .options
    path: Path | None  # the model file, or None: not written
    summary: dict  # the numbers of ``translucency fit --json``: rounds, Φ per round, flags, estimates

    @property
    def model(self):
        """The fitted model (``result.model``)."""
        return self.result.model


def fit_model(
    dataset,
    family: str = "auto",
    out=None,
    *,
    n_terms: int | str | None = None,
    n_directions: int | str | None = None,
    colour: str | None = None,
    weighting: str = "poisson",
    max_rounds: int = 3,
    exclusion_mm: float | None = None,
    alpha_radius: float | None = None,
    chunk_points: int | None = None,
    float16: bool = False,
    overwrite: bool = False,
    scheduler: str | None = "threads",
    max_memory: str | int | None = None,
    reporter: Reporter | None = None,
    **options,
) -> Fitting:
    """Fit a model family per incident point, with the modulation texture α, to a planar or mesh data set.

    ``translucency fit`` is this function: the same checks, estimates, fit and file.  An interrupted
    planar fit with ``out`` resumes from ``OUT.partial.npz`` when called again with the same arguments.

    Parameters
    ----------
    dataset : PlanarDataset, MeshDataset or path
        The measurement (:func:`translucency.open_dataset`).
    family : {"auto", "iso", "aniso", "dipole", "burley", "pbd", "ddipole"}
        The model family (:data:`translucency.fit.FAMILIES`): the paper's isotropic or anisotropic sum
        of exponentials, or a baseline (meshes: iso, dipole, burley); ``"auto"`` (default): the sum of
        exponentials with its structure — colour, n, m (planar) — chosen by held-out error on the data's
        own photons (:mod:`translucency.fit.structure`; the choice is in ``summary["structure"]``).
    out : str or Path, optional
        The model file to write (``.model.zip``); default: none written, the fit is returned.
    n_terms, n_directions : int, "auto" or None
        Exponential terms per profile (1–4) and directions m of the anisotropic model (planar data);
        ``"auto"`` chooses by held-out error.  None: chosen with ``family="auto"``, else n = 3, m = 8.
    colour : {"shared", "per-channel", "auto"}, optional
        One fall-off scaled per channel (the paper's) or one per channel; None: chosen with
        ``family="auto"``, else per channel.
    weighting : {"poisson", "relative"}
        The residuals' weights (mesh fits: poisson only).
    max_rounds : int
        Most alternation rounds (parameters, then α).
    exclusion_mm : float, optional
        Pixels (vertices) closer than this to x_i are ignored; default one pixel (half an edge).
    alpha_radius : float, optional
        Pool α's statistics over this distance, mm (sparse or noisy data).
    chunk_points : int, optional
        Planar incident points read and fitted together (default: an eighth of the points, 128–512).
    float16 : bool
        Store the parameters as float16 (a smaller file).
    overwrite : bool
        Replace a model file of translucency at ``out`` (never anything else).
    scheduler : str, optional
        ``"threads"``, ``"local:N"`` or ``"tcp://HOST:PORT"``; the fit is the same.
    max_memory : str or int, optional
        Most memory the fit may use (``"4G"``); a larger estimate is refused before any work.
    reporter : Reporter, optional
        Hears the run's information lines and progress (default: silent).
    **options
        Further options of the stage function (``rel_sigma``, ``tol``, …).

    Returns
    -------
    Fitting
        ``.result`` (:class:`translucency.fit.FitResult`), ``.model``, ``.path``, ``.summary``.

    Raises
    ------
    TranslucencyError
        A bad argument (named), a damaged or unfinished data set, ``out`` not writable.

    Examples
    --------
    The embedded scan, two exponential terms, one round (seconds; the defaults choose the structure and
    take up to three rounds, about a minute):

    >>> import translucency as tl
    >>> fitting = tl.fit_model(tl.data.default_dataset(), "iso", n_terms=2, max_rounds=1)
    >>> fitting.model.n_points, fitting.model.n_terms, fitting.summary["rounds"], fitting.path
    (1024, 2, 1, None)
    """
    # the arguments first (no file read), then the data set and what it implies, then the output, then work
    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    max_rounds = whole_number("max_rounds", max_rounds)
    check_option("exclusion_mm", exclusion_mm, lo=0)
    check_option("chunk_points", chunk_points, lo=1)
    check_option("alpha_radius", alpha_radius, lo=0)
    n_terms, n_directions = _count_or_auto("n_terms", n_terms), _count_or_auto("n_directions", n_directions)
    data = _data_set(dataset)
    on_mesh = isinstance(data, MeshDataset)
    stage = fit_mesh if on_mesh else fit_planar
    refuse_unknown(f"fit on a {'mesh' if on_mesh else 'planar'} data set", options, stage)
    if on_mesh:  # what a per-vertex fit does not take, one line each
        _refuse_on_mesh(data, family, weighting)
    # the family the estimates count (the richest a choice may fit), and whether a structure is chosen
    checked, n, m, c, free, _ = resolve_structure(family, n_terms, None if on_mesh else n_directions, colour,
                                                  planar=not on_mesh)  # fmt: skip
    check_fit_options(checked, n, m, c, weighting=weighting)
    # a chosen structure has its own time terms and calibration ("fit auto": the choice and the fit)
    run = Run("fit", max_memory=max_memory, reporter=reporter, timer="fit auto" if free else f"fit {checked}")
    estimate = {"family": checked, "n_terms": n, "n_directions": m, "colour": c}
    out = None if out is None else Path(out)
    if out is not None:
        claim_output(out, "model file", overwrite=overwrite, inputs=[data.path], option="out")
    data.check_complete()  # a damaged or unfinished data set: one line, before any work
    args = dict(n_terms=n_terms, colour=colour, exclusion_mm=exclusion_mm, max_rounds=max_rounds)
    args.update(alpha_radius=alpha_radius, scheduler=scheduler, **options)
    if on_mesh:
        result = _fit_mesh(run, data, family, out, args, estimate)
        meta = result.metadata(Path(data.path).resolve())
    else:
        args.update(n_directions=n_directions, weighting=weighting, chunk_points=chunk_points)
        result = _fit_planar(run, data, family, out, args, estimate)
        meta = {**result.metadata(data.path), "dataset_identity": dataset_identity(data.header)}
    path = None if out is None else _save(result, out, meta, float16, overwrite)
    record = _record(result, path, data, on_mesh)  # the warnings for flagged and unphysical points too
    return Fitting(result, path, run.summary(record))


def _refuse_on_mesh(data: MeshDataset, family: str, weighting: str) -> None:
    """Refuse what a per-vertex fit does not take: a directional family, a weighting other than Poisson."""
    if family in FAMILIES and FAMILIES[family].directional:
        raise TranslucencyError(
            f"family={family!r}: the anisotropic model is for planar data sets; {data.path} is a "
            "mesh data set, where the isotropic model is fitted per vertex (r = |x_o - x_i|, as in the "
            "paper): use family='iso'"
        )
    if weighting != "poisson":
        raise TranslucencyError("weighting: mesh fits weight by the Poisson variance only")


def _save(result: FitResult, out: Path, meta: dict, float16: bool, overwrite: bool) -> Path:
    """Write the fitted model to ``out`` (parameters as float16 or float32) with its metadata."""
    dtype = "float16" if float16 else "float32"
    return save_model(result.model, out, dtype=dtype, meta=meta, overwrite=overwrite)


def _data_set(dataset) -> PlanarDataset | MeshDataset:
    """The data set of ``dataset`` (a path is checked to hold one: a model or mesh file is named so)."""
    if isinstance(dataset, (str, os.PathLike)):
        expect_input(Path(dataset), DATA_SETS)
        dataset = open_any_dataset(dataset)
    if not isinstance(dataset, (PlanarDataset, MeshDataset)):
        raise TranslucencyError(f"dataset: expected a data set or its path, got {type(dataset).__name__}")
    return dataset


def _count_or_auto(name: str, value):
    """``"auto"``, None (the default) or a whole number (its range is checked with the model:
    ``check_fit_options``)."""
    if value is None:
        return None
    if isinstance(value, str):
        text = value.strip().lower()
        if text == "auto":
            return "auto"
        try:
            return int(text)
        except ValueError:
            raise TranslucencyError(f"{name}: expected a whole number or 'auto', got {value!r}") from None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TranslucencyError(f"{name}: expected a whole number or 'auto', got {value!r}")
    return int(value)


def _fit_mesh(run: Run, data: MeshDataset, family: str, out: Path | None, args: dict, est: dict) -> FitResult:
    """The per-vertex fit under ``run``: its estimates (``est``: the family and options they count), then
    :func:`translucency.fit.fit_mesh`."""
    V = int(data.header["n_vertices"])
    params = FAMILIES[est["family"]].params_per_point(est["n_terms"], 1, est["colour"])
    workers = os.cpu_count() or 1
    need = resources.memory.mesh_fit(
        points=data.n_points, vertices=V, chunk=MESH_FIT_CHUNK, workers=workers, params=params
    )
    run.check(need, out)
    units = resources.timing.fit_units(points=data.n_points, pixels=V, rounds=args["max_rounds"])
    timing = run.time(units)
    run.info(f"fit {family} on {data.n_points} incident points x {V:,} vertices; time {timing.text()}")
    with run.work(f"fit {family} per vertex") as work:
        return fit_mesh(data.path, family, progress=work.step(), **args)


def _fit_planar(
    run: Run, data: PlanarDataset, family: str, out: Path | None, args: dict, est: dict
) -> FitResult:
    """The planar fit under ``run``: its estimates (``est``: the family and options they count), a
    checkpoint beside ``out`` to resume from, then :func:`translucency.fit.fit_planar`."""
    chunk = None if args["chunk_points"] is None else min(args["chunk_points"], data.n_points)
    H, W = data.window
    stored = int(data.group["R_d"].chunks[0])
    params = FAMILIES[est["family"]].params_per_point(est["n_terms"], est["n_directions"], est["colour"])
    need = resources.memory.planar_fit(
        points=data.n_points,
        pixels=H * W,
        chunk=chunk or default_chunk_points(data.n_points, stored),
        workers=os.cpu_count() or 1,
        params=params,
        block=FIT_BLOCK,
    )
    run.check(need, out)
    ckpt = None if out is None else out.with_name(out.name + ".partial.npz")
    done = _rounds_done(ckpt)  # a checkpoint of an interrupted fit: only the rounds left are estimated
    max_rounds = args["max_rounds"]
    units = resources.timing.fit_units(
        points=data.n_points, pixels=H * W, rounds=max(1, max_rounds - (done or 0))
    )
    timing = run.time(units)
    if ckpt is not None:
        run.kept = lambda: (
            f"the fit's state is kept in {ckpt}; re-run the same command to resume"
            if ckpt.exists()
            else "nothing kept (the fit saves its state after its first chunk)"
        )
    resuming = "" if done is None else f"resuming from {ckpt} ({done}/{max_rounds} rounds done): "
    run.info(
        f"{resuming}fit {family} on {data.n_points} incident points x {H * W:,} pixels; time {timing.text()}"
    )
    with run.work(f"fit {family}", fresh=ckpt is None or not ckpt.exists()) as work:
        return fit_planar(
            data, family, checkpoint=ckpt, progress=work.step(), **{**args, "chunk_points": chunk}
        )


def _rounds_done(ckpt: Path | None) -> int | None:
    """Rounds an interrupted fit finished, from its checkpoint (None: no readable checkpoint)."""
    if ckpt is None or not ckpt.is_file():
        return None
    try:
        with np.load(ckpt) as z:
            return int(np.asarray(z["round"]).ravel()[0])
    except Exception:  # noqa: BLE001 — an unreadable checkpoint is not used (the fit starts afresh)
        return None


def _record(result: FitResult, path: Path | None, data, on_mesh: bool) -> dict:
    """The fit's summary (``translucency fit --json``), with a warning for flagged or unphysical points."""
    flagged = np.flatnonzero(result.flagged).tolist()
    if not on_mesh and flagged:
        warnings.warn(
            f"{len(flagged)} incident points have no usable data (all masked, NaN or zero) and are flagged "
            f"in the model: {flagged[:10]}…",
            stacklevel=3,
        )
    bad = _unphysical(result.model, path)
    return {
        "command": "fit",
        "model": path,
        "dataset": data.path,
        "kind": result.model.kind,
        "geometry": result.model.geometry,
        "n_points": result.model.n_points,
        "rounds": len(result.history),
        "objective_per_round": result.history,
        "seconds": round(result.seconds, 3),
        "flagged_points": flagged,
        "unphysical_points": bad,
        "structure": result.options.get("structure"),  # the held-out choice (None: the structure given)
    }


def _unphysical(model, path: Path | None) -> list[int]:
    """The points where the model breaks a physical bound (:func:`translucency.model.check_physics`), with
    one warning naming them."""
    # what the stored values promise where a file was written (float16 rounds them), else the model's
    physics = read_header(path)["physics"] if path is not None else check_physics(model).summary()
    bad = sorted(set(physics["over_albedo"]) | set(physics["beyond_object"]))
    if bad:
        where = f"; see `translucency info {path}`" if path is not None else ""
        warnings.warn(
            f"{len(bad)} incident points are not physical (total reflectance up to "
            f"{physics['max_total_reflectance']:.3g}, up to {100 * physics.get('max_beyond_object', 0):.3g}% "
            f"of a point's energy beyond {physics.get('object', 'the object')}): "
            f"{bad[:10]}{'…' if len(bad) > 10 else ''}{where}",
            stacklevel=3,
        )
    return bad
