"""The evaluation report of per-vertex fits on a mesh data set.

:func:`write_mesh_report` takes one or more per-vertex models of the same object and writes, into a
directory:

``mesh_errors.png``  every model's error against distance with the reference's noise floor, and the first
                     model's error per vertex on the object (:mod:`.mesh_figure`);
``report.json``      rel_l2 overall and per band (near < 1 mm, mid 1–4 mm, far > 4 mm), the noise floor,
                     the error beyond it, energies, per incident point, per model (:data:`MESH_DEFINITIONS`);
``index.html``       the table and the figure.

The numbers are :func:`.mesh_errors.mesh_errors`; with a truth (an independent acquisition of the same
mesh and incident vertices) they are against it, the in-sample numbers beside them under ``in_sample``.
"""

from __future__ import annotations

import html
import shlex
import sys
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from .._version import __version__
from ..io.atomic import write_json
from ..io.mesh_dataset import MeshDataset, open_mesh_dataset
from ..medium import medium_of
from ..model.bounds import check_physics
from .errors import BANDS, finite_or_null
from .labels import labelled_models, noise_label, table_caption
from .mesh_errors import check_same_points, mesh_errors
from .mesh_figure import plot_mesh_errors
from .oblique_errors import oblique_errors
from .summary import _relative

#: what each number of a mesh report means (report.json "definition", the page)
MESH_DEFINITIONS = {
    "rel_l2": "||model - reference||_2 / ||reference||_2 over the pairs (x_i, v) of incident vertex and "
    "vertex with r = |v - x_i| >= the fit's exclusion radius (half the mean edge: the incident vertex's "
    "own tally is left out), RGB summed; rel_l2_near/mid/far over r < 1 mm / 1-4 mm / > 4 mm. The "
    "reference is the truth when there is one, else the fitted data",
    "noise_floor": "sqrt(sum of the reference's variance) / ||reference||, the variance of a barycentric "
    "tally R_d / (2 N A_v) (N photons, A_v the vertex's area): what a perfect model scores",
    "beyond_noise": "sqrt(max(||model - truth||^2 - sum variance, 0)) / ||truth||: the error left after the "
    "truth's own (independent) noise; null in-sample",
    "energy_error": "per incident point the energy sum A_v R_d over a band's vertices (or all: 'surface'), "
    "model against reference, relative L2 over the points",
    "energy_noise": "the reference's noise of those energies",
    "per_point": "the relative error of each incident point (values, in the data set's order; null: "
    "flagged), its median and 95th percentile",
    "by_distance": "rel_l2 and the noise floor per ring of r (edges_mm), and the number of pairs",
    "in_sample": "the same numbers against the data the model was fitted to",
}


def write_mesh_report(
    models,
    dataset,
    out_dir,
    *,
    truth=None,
    flagged=None,
    exclusion=None,
    json_path=None,
    command: str | None = None,
    through: bool | None = None,
) -> dict:
    """Evaluate per-vertex models on a mesh data set (or on an independent truth) and write the report.

    Parameters
    ----------
    models : ReflectanceModel or sequence of them, or dict label -> model
        The first is the primary model (its numbers are also the JSON's top level).
    dataset : MeshDataset or path
        The data set the models were fitted to.
    out_dir : path
        Report directory.
    truth : MeshDataset or path, optional
        An independent acquisition of the same mesh and incident vertices (another seed).
    flagged, exclusion : dict label -> bool array / float, optional
        Points each fit flagged (left out); the exclusion radius each fit used (mm).
    json_path : path, optional
        Also write the JSON summary here.
    command : str, optional
        The command that made the report (default: this process's command line).
    through : bool, optional
        Each model's through-body table in its predictions: default, wherever it holds one (as ``render``
        draws it); False: the paper's model (:func:`~translucency.evaluate.mesh_errors.mesh_errors`).

    Returns
    -------
    dict
        The JSON summary; an empty band's numbers are NaN here and null in the files.
    """
    ds = dataset if isinstance(dataset, MeshDataset) else open_mesh_dataset(dataset)
    models = labelled_models(models)
    flagged, exclusion = flagged or {}, exclusion or {}
    if truth is not None:
        truth = truth if isinstance(truth, MeshDataset) else open_mesh_dataset(truth)
        check_same_points(ds, truth)

    def errors_on(data, name, m):
        return mesh_errors(
            m, data, flagged=flagged.get(name), exclusion_mm=exclusion.get(name), through=through
        )

    in_sample = {name: errors_on(ds, name, m) for name, m in models.items()}
    held_out = None if truth is None else {name: errors_on(truth, name, m) for name, m in models.items()}
    errors = held_out or in_sample
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    plot_mesh_errors(
        errors,
        ds["vertices"],
        ds["faces"],
        ds["incident"],
        out_dir / "mesh_errors.png",
        held_out=truth is not None,
    )
    per_model = {
        name: _model_summary(
            name, e, models[name], in_sample[name], held_out, truth or ds, flagged, exclusion
        )
        for name, e in errors.items()
    }
    summary = _report_summary(ds, truth, out_dir, command, next(iter(models)), per_model)
    strict = finite_or_null(summary)  # no NaN in the files: an empty band is null
    write_json(out_dir / "report.json", strict)
    if json_path is not None:
        write_json(json_path, strict)
    (out_dir / "index.html").write_text(_page(strict), encoding="utf-8")
    return summary


def _model_summary(name, e, model, in_sample, held_out, reference, flagged: dict, exclusion: dict) -> dict:
    """A model's JSON fields: its errors, flagged points, physics, in-sample errors and oblique beams."""
    s = e.summary()
    if held_out is None:
        s["beyond_noise"] = None  # in-sample: the fit has followed the noise
    fl = flagged.get(name)
    s["flagged_points"] = [] if fl is None else np.flatnonzero(fl).tolist()
    s["physics"] = check_physics(model).summary()
    if held_out is not None:
        s_in = in_sample.summary()
        s_in.pop("beyond_noise", None)
        s["in_sample"] = s_in
    # light arriving at an angle: the oblique beams of the truth (or the data), with and without the lean
    oblique = oblique_errors(model, reference, exclusion_mm=exclusion.get(name))
    if oblique is not None:
        s["oblique"] = oblique
    medium = medium_of(model)  # the medium the fit estimated from the scan, as info states it
    if medium is not None:
        s["medium"] = medium.summary()
    return s


def _report_summary(ds, truth, out_dir: Path, command, first: str, per_model: dict) -> dict:
    """The report's JSON summary: provenance, what was compared, the first model's fields, every model's."""
    return {
        "written_by": f"translucency {__version__}",
        "command_line": command
        if command is not None
        else shlex.join([Path(sys.argv[0]).name, *sys.argv[1:]]),
        "date": datetime.now(UTC).isoformat(timespec="seconds"),
        "geometry": "mesh",
        "dataset": _relative(ds.path, out_dir),
        "truth": None if truth is None else _relative(truth.path, out_dir),
        "paths": "relative to this report's folder",
        "evaluated_against": "truth (independent acquisition)" if truth is not None else "the fitted data",
        "photons": {
            "dataset": ds.header["photons"],
            "truth": None if truth is None else truth.header["photons"],
        },
        "model": first,
        **per_model[first],
        "bands_mm": {k: [lo, hi if np.isfinite(hi) else None] for k, (lo, hi) in BANDS.items()},
        "models": per_model,
        "definition": MESH_DEFINITIONS,
    }


def _pct(v) -> str:
    """A table cell's percentage ('–' for null)."""
    return "–" if v is None else f"{100 * v:.2f}&nbsp;%"


def _band_row(label: str, cells) -> str:
    """A table row: its label, then the percentages overall and per band."""
    return f"<tr><td>{label}</td>" + "".join(f"<td>{_pct(v)}</td>" for v in cells) + "</tr>"


def _model_rows(name: str, m: dict) -> list[str]:
    """A model's table rows: its errors, beyond the noise, on the oblique beams and in-sample."""
    rows = [_band_row(html.escape(name), [m["rel_l2"], m["rel_l2_near"], m["rel_l2_mid"], m["rel_l2_far"]])]
    if m.get("beyond_noise"):
        b = m["beyond_noise"]
        rows.append(_band_row("&nbsp;beyond the noise", [b["all"], b["near"], b["mid"], b["far"]]))
    if m.get("oblique"):
        ob = m["oblique"]
        lean = "" if ob["lean"] is None else f", with its lean {_pct(ob['lean'])}"
        rows.append(
            f"<tr><td colspan='5'>&nbsp;oblique beams ({ob['beams']} a point): the paper's model "
            f"{_pct(ob['paper'])}{lean}; noise {_pct(ob['noise'])}</td></tr>"
        )
    if m.get("in_sample"):
        i = m["in_sample"]
        rows.append(
            _band_row("&nbsp;in-sample", [i["rel_l2"], i["rel_l2_near"], i["rel_l2_mid"], i["rel_l2_far"]])
        )
    return rows


def _page(s: dict) -> str:
    """The report's HTML page: one sentence on what was compared, the table, the figure, the definitions."""
    against = (
        "the independent truth " + html.escape(str(s["truth"]))
        if s["truth"]
        else "the fitted data (in-sample)"
    )
    bands = ("near &lt;1 mm", "mid 1–4 mm", "far &gt;4 mm from the light")
    head = "".join(f"<th>{h}</th>" for h in ("model", "all", *bands))
    rows = [row for name, m in s["models"].items() for row in _model_rows(name, m)]
    nf = s["noise_floor"]
    noise = noise_label(s["truth"] is not None)
    rows.append(_band_row(f"<i>{noise}</i>", [nf[k] for k in ("all", *BANDS)]))
    first = s["models"][s["model"]]
    verdict = (
        f"{html.escape(s['model'])}: {_pct(first['rel_l2'])} overall "
        f"against a noise floor of {_pct(nf['all'])}"
    )
    if first.get("beyond_noise"):
        verdict += (
            f"; {_pct(first['beyond_noise']['all'])} beyond the truth's noise, "
            f"{_pct(first['in_sample']['rel_l2'])} in-sample"
        )
    defs = "".join(f"<dt>{html.escape(k)}</dt><dd>{html.escape(v)}</dd>" for k, v in s["definition"].items())
    return (
        "<!doctype html><html><head><meta charset='utf-8'><title>translucency: mesh evaluation</title>"
        "<style>body{font-family:sans-serif;max-width:1400px;margin:1em auto}td,th{padding:2px 10px;"
        "text-align:right;white-space:nowrap}td:first-child{text-align:left}img{max-width:100%}</style>"
        f"</head><body><h1>Per-vertex models on {html.escape(str(s['dataset']))}</h1>"
        f"<p>Relative L2 error of R_d per pair of incident vertex and vertex, against {against}. "
        f"{verdict}.</p>"
        f"<table><tr>{head}</tr>{''.join(rows)}</table>"
        f"<p><small>{html.escape(table_caption(s['truth'] is not None, 'vertices'))}</small></p>"
        "<p><img src='mesh_errors.png' alt='error against distance and per vertex'></p>"
        f"<dl>{defs}</dl><p><small>{html.escape(s['written_by'])}, {html.escape(s['date'])}: "
        f"<code>{html.escape(s['command_line'])}</code></small></p></body></html>"
    )
