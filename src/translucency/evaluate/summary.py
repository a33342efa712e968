"""The report's JSON summary: per model rel_l2 overall and per band, noise floors, flagged points, physics."""

from __future__ import annotations

import os
import shlex
import sys
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from .._version import __version__
from ..model.bounds import check_physics
from .conclusion import conclusion
from .errors import BANDS

#: what each number of the report means (report.json "definition", the HTML page)
DEFINITIONS = {
    "rel_l2": "||model - reference||_2 / ||reference||_2 over the valid pairs (x_i, x_o) (mask, finite, "
    "r >= the fit's exclusion radius, default one pixel), RGB summed; rel_l2_near/mid/far the same over "
    "r < 1 mm / 1-4 mm / > 4 mm. The reference is the truth when there is one, else the fitted data",
    "noise_floor": "sqrt(sum of the reference's variance) / ||reference||: what a perfect model scores",
    "beyond_noise": "sqrt(max(||model - truth||^2 - sum variance, 0)) / ||truth||: the error left after the "
    "truth's own (independent) noise, an estimate of the error against the noise-free material; "
    "null in-sample",
    "energy_error": "per incident point the energy sum R_d p^2 over a band (near, mid, far) or the whole "
    "window, model against reference, relative L2 over the points; 'total': the model's closed-form total "
    "diffuse reflectance (x mean alpha) against the reference's tally of every exit",
    "energy_noise": "the reference's noise of those energies",
    "in_sample": "the same numbers against the data the model was fitted to",
    "per_point": "median and 95th percentile of the per-incident-point relative error",
}


def _relative(path, base: Path) -> str:
    """``path`` relative to ``base`` (as given when on another drive)."""
    try:
        return os.path.relpath(Path(path).resolve(), base.resolve())
    except ValueError:  # another drive
        return str(path)


def report_summary(
    models: dict,
    in_sample: dict,
    held_out: dict | None,
    *,
    flagged: dict,
    dataset,
    truth,
    out_dir: Path,
    points: list,
    fine: dict | None,
    command: str | None,
) -> dict:
    """The report's summary (``report.json`` before NaN become null): every model's errors
    (:meth:`~translucency.evaluate.errors.PlanarErrors.summary`, held-out when ``held_out`` is given, with
    the in-sample numbers beside them), flagged points and physics check, with the provenance of the
    report (version, command line, date, data paths relative to ``out_dir``), :data:`DEFINITIONS` and
    ``"summary"``: the conclusion in a few sentences (:func:`.conclusion.conclusion`)."""
    errors = held_out or in_sample
    first = next(iter(models))
    per_model = {}
    for name, e in errors.items():
        per_model[name] = e.summary()
        if held_out is None:
            per_model[name]["beyond_noise"] = None  # in-sample: the fit has followed the noise
        fl = flagged.get(name)
        per_model[name]["flagged_points"] = [] if fl is None else np.flatnonzero(fl).tolist()
        per_model[name]["physics"] = check_physics(models[name]).summary()
        if held_out is not None:
            s_in = in_sample[name].summary()
            s_in.pop("beyond_noise", None)
            per_model[name]["in_sample"] = s_in
    return {
        "written_by": f"translucency {__version__}",
        "command_line": command
        if command is not None
        else shlex.join([Path(sys.argv[0]).name, *sys.argv[1:]]),
        "date": datetime.now(UTC).isoformat(timespec="seconds"),
        "dataset": _relative(dataset.path, out_dir),
        "truth": None if truth is None else _relative(truth.path, out_dir),
        "paths": "relative to this report's folder",
        "evaluated_against": "truth (independent acquisition)" if truth is not None else "the fitted data",
        "summary": conclusion(per_model, models, held_out=held_out is not None, n_points=dataset.n_points),
        "model": first,
        **per_model[first],
        "bands_mm": {k: [lo, hi if np.isfinite(hi) else None] for k, (lo, hi) in BANDS.items()},
        "models": per_model,
        "profile_points": points,
        "fine_profiles": None
        if fine is None
        else {"bin_mm": float(fine["edges_mm"][1] - fine["edges_mm"][0]), "photons": int(fine["photons"])},
        "definition": DEFINITIONS,
    }
