"""The evaluation report of planar fits: the paper's Figure 1 and the numbers behind it.

:func:`write_report` takes one or more fitted models of the same data set and
writes, into a directory:

``profiles.png``     ring-averaged R_d around chosen incident points, measured and
                     every model, log scale (Figure 1, left);
``error_maps.png``   relative error per outgoing pixel and per incident point of
                     every model, one colour scale with a colour bar (Figure 1, right);
``error_ratios.png`` each model's error per incident point over the first model's;
``alpha.png``        the modulation texture α of every model;
``params.png``       maps of the first model's parameters over the incident points;
``report.json``      rel_l2 overall and per band (near < 1 mm, mid 1–4 mm, far > 4 mm),
                     noise floors, flagged points, per model, and ``summary``: what to conclude
                     from them, in a few sentences;
``index.html``       the summary on top, then all of it side by side.

This module puts the report together; the figures are drawn in :mod:`.profile_figure`,
:mod:`.error_maps` and :mod:`.model_maps`, the numbers summed up in :mod:`.summary` (the summary's
sentences in :mod:`.conclusion`) and the page written in :mod:`.page`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..cluster import open_cluster
from ..io.atomic import write_json
from ..io.dataset import PlanarDataset, open_dataset
from .error_maps import plot_error_maps, plot_error_ratios
from .errors import finite_or_null, planar_errors
from .labels import model_label
from .model_maps import plot_alpha, plot_parameters
from .page import write_page
from .profile_figure import default_points, plot_profiles
from .summary import report_summary


def _load_fine(fine):
    """The fine ring profiles: as given (a dict, or None), or read from their .npz file."""
    if fine is None or isinstance(fine, dict):
        return fine
    with np.load(fine) as z:
        return {k: z[k] for k in z.files}


def write_report(
    models,
    dataset,
    out_dir,
    *,
    points=None,
    flagged=None,
    json_path=None,
    extra=None,
    truth=None,
    exclusion=None,
    fine=None,
    command: str | None = None,
    scheduler=None,
) -> dict:
    """Evaluate models on a planar data set and write the figures, JSON and HTML report.

    ``scheduler``: where the errors' chunks are computed (``"threads"``, ``"local:N"``,
    ``"tcp://HOST:PORT"`` or an open :class:`translucency.cluster.Cluster`); the report is the same.

    With ``truth`` (an independent acquisition of the same sample and incident points: another photon
    seed, usually more photons) every figure and headline number is against the truth, the error beyond
    the truth's own noise stands beside it, and the in-sample errors (against the data the models were
    fitted to) under ``in_sample``.

    Parameters
    ----------
    models : ReflectanceModel or sequence of them, or dict label -> model
        The first is the primary model (its numbers are also the JSON's top level).
    dataset : PlanarDataset or path
    out_dir : path
        Report directory.
    points : list of int, optional
        Incident points for the profiles; default the points of ``fine``, else :func:`default_points`.
    flagged : dict label -> bool array, optional
        Points each fit flagged (left out of its errors and listed).
    json_path : path, optional
        Also write the JSON summary here.
    extra : list of (file name, caption), optional
        Further figures already in ``out_dir`` to show in the HTML page.
    truth : PlanarDataset or path, optional
        The held-out truth.
    exclusion : dict label -> float, optional
        The exclusion radius (mm) each fit used; pairs closer are not evaluated (default one pixel).
    fine : dict or path (.npz), optional
        Ring profiles of the truth on a fine radial grid around some incident points
        (:func:`translucency.pipeline.fine_profiles`): the near-x_i rows of the profile figure.
    command : str, optional
        The command that made the report (default: this process's command line).

    Returns
    -------
    dict
        The JSON summary; an empty band's numbers are NaN here and null in the files.
    """
    ds = dataset if isinstance(dataset, PlanarDataset) else open_dataset(dataset)
    if not isinstance(models, dict):
        models = list(models) if isinstance(models, (list, tuple)) else [models]
        models = {model_label(m): m for m in models}
    flagged = flagged or {}
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    exclusion = exclusion or {}
    fine = _load_fine(fine)
    truth = None if truth is None else truth if isinstance(truth, PlanarDataset) else open_dataset(truth)
    in_sample, held_out = _all_errors(models, ds, truth, flagged, exclusion, scheduler)
    if points is None:
        points = [int(p) for p in fine["points"]] if fine is not None else default_points(ds.n_points)
    points = list(points)
    _draw_figures(models, held_out or in_sample, ds, truth, points, fine, exclusion, out_dir)
    summary = report_summary(
        models,
        in_sample,
        held_out,
        flagged=flagged,
        dataset=ds,
        truth=truth,
        out_dir=out_dir,
        points=points,
        fine=fine,
        command=command,
    )
    strict = finite_or_null(summary)  # no NaN in the files: an empty band is null
    write_json(out_dir / "report.json", strict)
    if json_path is not None:
        write_json(json_path, strict)
    write_page(out_dir / "index.html", ds, strict, extra or [])
    return summary


def _all_errors(
    models: dict, ds, truth, flagged: dict, exclusion: dict, scheduler
) -> tuple[dict, dict | None]:
    """Every model's errors in-sample and (with a truth) held out; in-sample alone, none beyond the noise."""
    with open_cluster(scheduler) as cluster:  # one cluster (if any) for every model's errors

        def errors_on(data, name, m):
            return planar_errors(
                m, data, flagged=flagged.get(name), exclusion_mm=exclusion.get(name), scheduler=cluster
            )

        in_sample = {name: errors_on(ds, name, m) for name, m in models.items()}
        held_out = None if truth is None else {name: errors_on(truth, name, m) for name, m in models.items()}
    if truth is None:
        for e in in_sample.values():  # against the fitted data the noise cannot be subtracted
            e.per_pixel_beyond = e.per_point_beyond = None
    return in_sample, held_out


def _draw_figures(
    models: dict, errors: dict, ds, truth, points: list, fine, exclusion: dict, out_dir: Path
) -> None:
    """The report's five figures: profiles, error maps, error ratios, α and the parameters."""
    shown = truth or ds
    plot_profiles(
        models,
        shown,
        points,
        out_dir / "profiles.png",
        fitted=ds if truth is not None else None,
        fine=fine if truth is not None else None,
        exclusion=exclusion,
    )
    plot_error_maps(errors, ds["x_i"], out_dir / "error_maps.png", models=models, held_out=truth is not None)
    plot_error_ratios(errors, ds["x_i"], out_dir / "error_ratios.png", models=models)
    plot_alpha(models, out_dir / "alpha.png")
    plot_parameters(models, out_dir / "params.png")
