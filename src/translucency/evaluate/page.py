"""The report's HTML page: the summary's table, the definitions and every figure side by side."""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_path
from ..io.dataset import PlanarDataset
from .labels import noise_label, table_caption


def _percent(v) -> str:
    """A table cell's percentage; a no-break space keeps the number and its unit on one line."""
    return "–" if v is None or not np.isfinite(v) else f"{100 * v:.2f}\u00a0%"


def write_page(path: Path, ds: PlanarDataset, summary: dict, extra: list) -> None:
    """Write the report's page to ``path``: the summary, the errors' table, the definitions, every figure.

    Parameters
    ----------
    path : Path
        The page (``index.html``), written atomically.
    ds : PlanarDataset
        The data set the models were fitted to (its points, windows and pitch are named).
    summary : dict
        The report's JSON summary (:func:`.summary.report_summary`, NaN as null).
    extra : list of (file name, caption)
        Further figures in the page's folder, shown last.
    """
    held_out = summary.get("truth") is not None
    rows = [_model_row(name, s, held_out) for name, s in summary["models"].items()]
    noise_cells = _noise_cells(next(iter(summary["models"].values())), held_out)
    noise = noise_label(held_out)
    against = (
        f"an independent acquisition of the same sample and incident points "
        f"(<code>{html.escape(summary['truth'])}</code>); 'in-sample' is against the fitted data"
        if held_out
        else "the data the models were fitted to (in-sample: a model that fits noise scores well here)"
    )
    own_noise = html.escape(table_caption(held_out).split(". ", 1)[1])
    if held_out:
        own_noise += " The last row's in-sample cell is the fitted data's own noise."
    beyond_head = "<th>beyond noise, all</th><th>beyond noise, near</th>" if held_out else ""
    in_head = "<th>in-sample, all</th>" if held_out else ""
    defs = _definitions(summary, held_out)
    figures = "".join(
        f'<figure><img src="{html.escape(f)}"><figcaption>{html.escape(c)}</figcaption></figure>'
        for f, c in extra
    )
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>translucency report</title>
<style>body{{font-family:sans-serif;max-width:1500px;margin:auto;padding:0 12px}}
table{{border-collapse:collapse}}
td,th{{border:1px solid #ccc;padding:4px 8px;text-align:right}} td{{white-space:nowrap}}
img{{max-width:100%}} .summary{{background:#f2f5f9;border-left:4px solid #3a7;padding:8px 12px}}</style>
</head><body>
<h1>Planar fit report</h1>
<p class="summary" id="summary">{html.escape(summary.get("summary") or "")}</p>
<p>{html.escape(summary["written_by"])}, {html.escape(summary["date"])}; command
<code>{html.escape(summary["command_line"])}</code>. Paths are relative to this page's folder.</p>
<p>Data set: <code>{html.escape(summary["dataset"])}</code> — {ds.n_points} incident points,
windows {ds.window[0]}×{ds.window[1]} px at {ds.pitch} mm.</p>
<h2>Errors</h2><p>Against {against}. Relative L2 error ‖model − R_d‖ / ‖R_d‖, RGB summed;
{html.escape(table_caption(held_out).split(". ", 1)[0])}.</p>
<table><tr><th>model</th><th>all</th><th>near &lt; 1 mm</th><th>mid 1–4 mm</th>
<th>far &gt; 4 mm from the light</th>
{beyond_head}<th>energy, near</th><th>energy, mid</th><th>total reflectance per point</th>{in_head}
<th>flagged points</th><th>unphysical points (ρ &gt; 1 or over half the energy beyond the sample)</th></tr>
{"".join(rows)}
<tr><th>{noise}</th>{noise_cells}</tr></table>
<p style="font-size:90%">{own_noise}</p>
<ul style="font-size:90%">{defs}</ul>
{_figure_captions(summary, held_out, noise)}
{figures}
</body></html>
"""
    with atomic_path(path) as tmp:
        tmp.write_text(page)


def _model_row(name: str, s: dict, held_out: bool) -> str:
    """A model's table row: its errors per band, beyond the noise, of the energies, in-sample, its flags."""
    cells = "".join(
        f"<td>{_percent(s[k])}</td>" for k in ("rel_l2", "rel_l2_near", "rel_l2_mid", "rel_l2_far")
    )
    if held_out:
        b = s.get("beyond_noise") or {}
        cells += f"<td>{_percent(b.get('all'))}</td><td>{_percent(b.get('near'))}</td>"
    en = s["energy_error"]
    cells += "".join(f"<td>{_percent(en.get(k))}</td>" for k in ("near", "mid", "total"))
    if held_out:
        cells += f"<td>{_percent(s['in_sample']['rel_l2'])}</td>"
    ph = s["physics"]
    unphysical = len(set(ph["over_albedo"]) | set(ph["beyond_object"]))
    max_rho = ph["max_total_reflectance"]
    return (
        f"<tr><th>{html.escape(name)}</th>{cells}<td>{len(s['flagged_points'])}</td>"
        f"<td>{unphysical} (max ρ {'–' if max_rho is None else f'{max_rho:.3g}'})</td></tr>"
    )


def _noise_cells(first: dict, held_out: bool) -> str:
    """The noise row's cells: the reference's noise per band and of the energies, in-sample beside it."""
    nf, ne = first["noise_floor"], first.get("energy_noise") or {}
    noise_cells = "".join(f"<td>{_percent(nf.get(k))}</td>" for k in ("all", "near", "mid", "far"))
    if held_out:
        noise_cells += "<td>0</td><td>0</td>"
    noise_cells += f"<td>{_percent(ne.get('near'))}</td><td>{_percent(ne.get('mid'))}</td><td></td>"
    if held_out:
        noise_cells += f"<td>{_percent(first['in_sample']['noise_floor']['all'])}</td>"
    noise_cells += "<td></td><td></td>"
    return noise_cells


def _definitions(summary: dict, held_out: bool) -> str:
    """The definitions' list items; in-sample without those of the truth's noise and the held-out numbers."""
    shown = (
        summary["definition"].items()
        if held_out
        else (  # in-sample: no truth's noise, no held-out
            (k, v) for k, v in summary["definition"].items() if k not in ("beyond_noise", "in_sample")
        )
    )
    return "".join(f"<li><b>{html.escape(k)}</b>: {html.escape(v)}</li>" for k, v in shown)


def _figure_captions(summary: dict, held_out: bool, noise: str) -> str:
    """The report's own five figures with their captions."""
    residual = "model / truth − 1" if held_out else "model / data − 1"
    beyond_row = ", the same beyond the truth's noise (black: within the noise)," if held_out else ""
    fine = summary.get("fine_profiles")
    fine_text = (
        ""
        if not fine
        else f" The lower two rows: the truth on {fine['bin_mm']:g} mm rings ({fine['photons']:,} photons "
        "per point and channel) against each model's ring means — the fits saw r ≥ the dotted line only."
    )
    profiles = '<figure><img src="profiles.png"><figcaption>Figure 1 (left): ring-averaged R_d around chosen '
    return (
        profiles
        + f"""incident points
(green channel), log scale; beneath each, {residual} with the ±1σ band of {noise} (grey).{fine_text}
</figcaption></figure>
<figure><img src="error_maps.png"><figcaption>Figure 1 (right): relative error per outgoing pixel (pairs
within 4 mm){beyond_row} and per incident point; one logarithmic colour scale per row, shared across
models, set by the data; {noise} marked on each colour bar (cyan line: its median, cyan band: 10–90 %).
Segments on an anisotropic model's map: its fitted direction of farthest spread, length ∝ (rms radius
along / across − 1).</figcaption></figure>
<figure><img src="error_ratios.png"><figcaption>Each model's error per incident point over the first
model's (blue: lower, red: higher; the reference's noise is in both), with an anisotropic model's fitted
directions.</figcaption></figure>
<figure><img src="alpha.png"><figcaption>Modulation texture α (dimensionless), one colour scale.
</figcaption></figure>
<figure><img src="params.png"><figcaption>Parameters of every model over the incident points, with units
(G: green channel).</figcaption></figure>"""
    )
