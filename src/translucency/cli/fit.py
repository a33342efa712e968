"""``translucency fit``: a model per incident point, with the modulation texture α, to a planar or a mesh
data set."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import typer

from .. import resources
from .._validate import TranslucencyError, check_option, check_undamaged
from ..io.dataset import dataset_identity, open_dataset
from ..io.inputs import DATA_SETS, expect_input
from ..io.mesh_dataset import is_mesh_dataset, open_mesh_dataset
from ..io.model_file import read_header, save_model
from ..io.outputs import claim_output
from ._common import (
    err_console,
    json_option,
    max_memory_option,
    overwrite_option,
    quiet_option,
    scheduler_option,
    user_errors,
)
from ._run import Run

#: points of a mesh fit's chunk (as ``translucency.fit.fit_mesh`` reads them; for the memory estimate)
MESH_FIT_CHUNK = 32


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
    from ..cluster import parse_scheduler  # heavy: the fitter loads Dask, SciPy and Numba only when it runs
    from ..fit import FAMILIES, FIT_BLOCK, check_fit_options, fit_mesh, fit_planar
    from ..fit.planar import default_chunk_points

    parse_scheduler(scheduler)  # a bad value or an unreachable cluster: one line, before work
    check_option("--rounds", rounds, lo=1)
    check_option("--exclusion", exclusion, lo=0)
    check_option("--chunk", chunk, lo=1)
    check_option("--alpha-radius", alpha_radius, lo=0)
    terms, directions = _count_or_auto("--terms", terms), _count_or_auto("--directions", directions)
    expect_input(data, DATA_SETS)  # a model or a mesh file where the data set belongs: say so
    run = Run("fit", max_memory=max_memory, quiet=quiet, timer=f"fit {model}")

    claim_output(out, "model file", overwrite=overwrite, inputs=[data], option="--out")
    workers = os.cpu_count() or 1
    on_mesh = is_mesh_dataset(data)
    if on_mesh:
        colour = colour or "shared"
        if model in FAMILIES and FAMILIES[model].directional:
            raise TranslucencyError(
                f"--model {model}: the anisotropic model is for planar data sets; {data} is a mesh data set, "
                "where the isotropic model is fitted per vertex (r = |x_o - x_i|, as in the paper): use "
                "--model iso"
            )
        if terms == "auto":
            raise TranslucencyError("--terms: 'auto' selects on planar data only; give n for a mesh fit")
        if weighting != "poisson":
            raise TranslucencyError("--weighting: mesh fits weight by the Poisson variance only")
        check_fit_options(model, terms, 1, colour, weighting=weighting)
        ds = open_mesh_dataset(data)
        _refuse_damaged(ds)
        V = int(ds.header["n_vertices"])
        need = resources.memory.mesh_fit(
            points=ds.n_points,
            vertices=V,
            chunk=MESH_FIT_CHUNK,
            workers=workers,
            params=FAMILIES[model].params_per_point(terms, 1, colour),
        )
        run.check(need, out)
        timing = run.time(resources.timing.fit_units(points=ds.n_points, pixels=V, rounds=rounds))
        run.info(f"fit {model} on {ds.n_points} incident points x {V:,} vertices; time {timing.text()}")
        with run.work(f"fit {model} per vertex") as work:
            result = fit_mesh(
                data,
                model,
                n_terms=terms,
                colour=colour,
                exclusion_mm=exclusion,
                max_rounds=rounds,
                alpha_radius=alpha_radius,
                progress=lambda done, total, msg: work.update(completed=done, total=total or None, item=msg),
                scheduler=scheduler,
            )
        meta = result.metadata(Path(data).resolve())
    else:
        colour = colour or "per-channel"
        check_fit_options(model, terms, directions, colour, weighting=weighting)
        ds = open_dataset(data)
        _refuse_damaged(ds)
        chunk = None if chunk is None else min(chunk, ds.n_points)  # a chunk beyond the data is the data
        H, W = ds.window
        stored = int(ds.group["R_d"].chunks[0])
        need = resources.memory.planar_fit(
            points=ds.n_points,
            pixels=H * W,
            chunk=chunk or default_chunk_points(ds.n_points, stored),
            workers=workers,
            params=FAMILIES[model].params_per_point(terms, directions, colour),
            block=FIT_BLOCK,
        )
        run.check(need, out)
        ckpt = out.with_name(out.name + ".partial.npz")
        done = _rounds_done(ckpt)  # a checkpoint of an interrupted fit: only the rounds left are estimated
        units = resources.timing.fit_units(
            points=ds.n_points,
            pixels=H * W,
            rounds=max(1, rounds - (done or 0)),
            candidates=_candidates(terms, directions),
        )
        timing = run.time(units)
        run.kept = lambda: (
            f"the fit's state is kept in {ckpt}; re-run the same command to resume"
            if ckpt.exists()
            else "nothing kept (the fit saves its state after its first chunk)"
        )
        resuming = "" if done is None else f"resuming from {ckpt} ({done}/{rounds} rounds done): "
        run.info(
            f"{resuming}fit {model} on {ds.n_points} incident points x {H * W:,} pixels; time {timing.text()}"
        )
        with run.work(f"fit {model}", fresh=not ckpt.exists()) as work:
            result = fit_planar(
                ds,
                model,
                n_terms=terms,
                n_directions=directions,
                colour=colour,
                exclusion_mm=exclusion,
                max_rounds=rounds,
                chunk_points=chunk,
                checkpoint=ckpt,
                progress=lambda done, total, msg: work.update(completed=done, total=total or None, item=msg),
                weighting=weighting,
                alpha_radius=alpha_radius,
                scheduler=scheduler,
            )
        meta = {**result.metadata(data), "dataset_identity": dataset_identity(ds.header)}
    path = save_model(
        result.model, out, dtype="float16" if float16 else "float32", meta=meta, overwrite=overwrite
    )
    if not on_mesh and result.flagged.any():
        err_console.print(
            f"[yellow]warning:[/] {int(result.flagged.sum())} incident points have no usable data "
            f"(all masked, NaN or zero) and are flagged in the model: "
            f"{np.flatnonzero(result.flagged)[:10].tolist()}…"
        )
    bad = _warn_unphysical(path)
    summary = {
        "command": "fit",
        "model": path,
        "dataset": data,
        "kind": result.model.kind,
        "geometry": result.model.geometry,
        "n_points": result.model.n_points,
        "rounds": len(result.history),
        "objective_per_round": result.history,
        "seconds": round(result.seconds, 3),
        "flagged_points": np.flatnonzero(result.flagged).tolist(),
        "unphysical_points": bad,
    }
    mesh_of = f", mesh of {len(result.model.alpha.values):,} vertices" if on_mesh else ""
    run.finish(
        as_json, summary, [f"model: {path} ({result.seconds:.1f} s, {len(result.history)} rounds{mesh_of})"]
    )


def _candidates(terms, directions) -> int:
    """Fits an ``auto`` choice runs for each point: n in 1..4 (``--terms auto``) x m in 1, 2, 4, 8, 16
    (``--directions auto``)."""
    return (4 if terms == "auto" else 1) * (5 if directions == "auto" else 1)


def _count_or_auto(option: str, value: str):
    """``auto`` or a whole number (the range is checked with the model: ``check_fit_options``)."""
    text = str(value).strip().lower()
    if text == "auto":
        return "auto"
    try:
        return int(text)
    except ValueError:
        raise TranslucencyError(f"{option}: expected a whole number or 'auto', got {value!r}") from None


def _rounds_done(ckpt: Path) -> int | None:
    """Rounds an interrupted fit finished, from its checkpoint (None: no readable checkpoint)."""
    if not ckpt.is_file():
        return None
    try:
        with np.load(ckpt) as z:
            return int(np.asarray(z["round"]).ravel()[0])
    except Exception:  # noqa: BLE001 — an unreadable checkpoint is not used (the fit starts afresh)
        return None


def _refuse_damaged(ds) -> None:
    """One line for an unfinished data set (an interrupted acquisition) or one with missing or
    undecodable chunks (``info`` lists them; re-running the acquisition with the same arguments
    finishes it, or repairs exactly those)."""
    check_undamaged(ds)
    done = np.asarray(ds.group["chunk_done"][...], dtype=bool)  # decodes: checked with the damage above
    if not done.all():
        raise TranslucencyError(
            f"{ds.path}: unfinished acquisition ({int(done.sum())}/{len(done)} chunks done); re-run the "
            "same `translucency acquire` command to finish it, then fit"
        )


def _warn_unphysical(path: Path) -> list[int]:
    """One warning line when the stored model breaks a physical bound (model/bounds.py); the points."""
    physics = read_header(path)["physics"]
    bad = sorted(set(physics["over_albedo"]) | set(physics["beyond_object"]))
    if bad:
        err_console.print(
            f"[yellow]warning:[/] {len(bad)} incident points are not physical (total reflectance up to "
            f"{physics['max_total_reflectance']:.3g}, up to {100 * physics.get('max_beyond_object', 0):.3g}% "
            f"of a point's energy beyond {physics.get('object', 'the object')}): "
            f"{bad[:10]}{'…' if len(bad) > 10 else ''}; see `translucency info {path}`"
        )
    return bad
