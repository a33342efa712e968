"""The evaluation report of planar fits: the paper's Figure 1 and the numbers behind it.

:func:`write_report` takes one or more fitted models of the same data set and
writes, into a directory:

``profiles.png``     ring-averaged R_d around chosen incident points, measured and
                     every model, log scale (Figure 1, left);
``error_maps.png``   relative error per outgoing pixel and per incident point of
                     every model, one colour scale with a colour bar (Figure 1, right);
``alpha.png``        the modulation texture α of every model;
``params.png``       maps of the first model's parameters over the incident points;
``report.json``      rel_l2 overall and per band (near < 1 mm, mid 1–4 mm, far > 4 mm),
                     noise floors, flagged points, per model;
``index.html``       all of it side by side.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from .._plotting import pyplot
from .._version import __version__
from ..io.atomic import atomic_path, write_json
from ..io.dataset import PlanarDataset, open_dataset
from ..model.bounds import check_physics
from .errors import BANDS, PlanarErrors, planar_errors
from .measured import ring_profile


def model_label(model) -> str:
    """A short name: 'iso n=3 (shared colour)', 'aniso m=8 n=3', 'dipole', 'burley'."""
    if model.kind != "exponential":
        return model.kind
    shape = "iso" if model.n_directions == 1 else f"aniso m={model.n_directions}"
    return f"{shape} n={model.n_terms}" + (" (shared colour)" if model.colour == "shared" else "")


def default_points(n_points: int) -> list[int]:
    """Four incident points spread over a square grid: centre, two off-centre, a corner."""
    side = int(round(np.sqrt(n_points)))
    picks = [
        side // 2 * side + side // 2,
        side // 4 * side + 3 * side // 4,
        3 * side // 4 * side + side // 4,
        0,
    ]
    return sorted({min(p, n_points - 1) for p in picks})


def _save(fig, path: Path) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    pyplot().close(fig)


def plot_profiles(models: dict, ds: PlanarDataset, points: list[int], path, channel: int = 1) -> None:
    """Figure 1 (left): ring means of measured and modelled R_d around each point, log scale."""
    plt = pyplot()
    fig, axes = plt.subplots(1, len(points), figsize=(4.2 * len(points), 3.8), squeeze=False)
    origin = ds["window_origin"]
    for ax, p in zip(axes[0], points):
        y = np.asarray(ds.group["R_d"][p, :, :, channel], dtype=np.float64)
        r, ym = ring_profile(y, ds.pitch)
        ax.semilogy(r, np.where(ym > 0, ym, np.nan), "ko", ms=3, label="measured (virtual DISCO)")
        for name, m in models.items():
            pred = m.R_d_window([p], origin[p : p + 1], ds.pitch, ds.window)[0, :, :, channel]
            _, pm = ring_profile(pred, ds.pitch)
            style = "-" if m.kind == "exponential" else "--"
            ax.semilogy(r, pm, style, lw=1.6, label=name)
        ax.set_title(f"x_i #{p} at ({ds['x_i'][p][0]:.1f}, {ds['x_i'][p][1]:.1f}) mm", fontsize=9)
        ax.set_xlabel("r [mm]")
        ax.set_ylabel("$R_d$ [mm$^{-2}$], " + "RGB"[channel])
        ax.grid(alpha=0.3, which="both")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    _save(fig, Path(path))


def plot_error_maps(errors: dict[str, PlanarErrors], x_i: np.ndarray, path) -> None:
    """Figure 1 (right): relative error per outgoing pixel and per incident point, shared colour scale."""
    plt = pyplot()
    names = list(errors)
    vmax = max(
        max(np.nanquantile(e.per_pixel, 0.98), np.nanquantile(e.per_point, 0.98)) for e in errors.values()
    )
    side = int(round(np.sqrt(len(x_i))))
    on_grid = side * side == len(x_i) and side > 1
    fig, axes = plt.subplots(2, len(names), figsize=(4.0 * len(names), 7.2), squeeze=False)
    for j, name in enumerate(names):
        e = errors[name]
        h, w = e.grid.shape
        ext = [
            e.grid.origin[0],
            e.grid.origin[0] + w * e.grid.pitch,
            e.grid.origin[1],
            e.grid.origin[1] + h * e.grid.pitch,
        ]
        im = axes[0][j].imshow(e.per_pixel, origin="lower", extent=ext, cmap="magma", vmin=0, vmax=vmax)
        axes[0][j].set_title(f"{name}\nper outgoing pixel, pairs r < {e.map_radius:g} mm", fontsize=9)
        lo, hi = x_i.min(axis=0) - 1.0, x_i.max(axis=0) + 1.0  # the scanned area
        axes[0][j].set_xlim(lo[0], hi[0])
        axes[0][j].set_ylim(lo[1], hi[1])
        if on_grid:  # a scan grid (rows of constant y): one pixel per incident point
            order = np.lexsort((x_i[:, 0], x_i[:, 1]))
            half = (x_i[:, 0].max() - x_i[:, 0].min()) / (side - 1) / 2
            sc = axes[1][j].imshow(
                e.per_point[order].reshape(side, side),
                origin="lower",
                cmap="magma",
                vmin=0,
                vmax=vmax,
                extent=[
                    x_i[:, 0].min() - half,
                    x_i[:, 0].max() + half,
                    x_i[:, 1].min() - half,
                    x_i[:, 1].max() + half,
                ],
            )
        else:
            sc = axes[1][j].scatter(
                x_i[:, 0], x_i[:, 1], c=e.per_point, cmap="magma", vmin=0, vmax=vmax, s=12, marker="s"
            )
        axes[1][j].set_aspect("equal")
        axes[1][j].set_title(f"per incident point (rel_l2 {100 * e.rel_l2:.1f} %)", fontsize=9)
        for ax in axes[:, j]:
            ax.set_xlabel("x [mm]")
            ax.set_ylabel("y [mm]")
    fig.colorbar(im, ax=axes[0].tolist(), label="relative L2 error", shrink=0.8)
    fig.colorbar(sc, ax=axes[1].tolist(), label="relative L2 error", shrink=0.8)
    _save(fig, Path(path))


def plot_alpha(models: dict, path) -> None:
    """The modulation texture α of each model."""
    plt = pyplot()
    fig, axes = plt.subplots(1, len(models), figsize=(4.0 * len(models), 3.6), squeeze=False)
    for ax, (name, m) in zip(axes[0], models.items()):
        a = m.alpha
        h, w = a.shape
        ext = [a.origin[0], a.origin[0] + w * a.pitch, a.origin[1], a.origin[1] + h * a.pitch]
        im = ax.imshow(
            a.values, origin="lower", extent=ext, cmap="gray", vmin=0, vmax=float(np.quantile(a.values, 0.99))
        )
        ax.set_title(f"α — {name}", fontsize=9)
        fig.colorbar(im, ax=ax, shrink=0.8)
    fig.tight_layout()
    _save(fig, Path(path))


def plot_parameters(model, path) -> None:
    """Maps over the incident points: total R_d (G), and the exponential terms' rates and weights."""
    plt = pyplot()
    x = model.x_i
    maps = {
        "total $R_d$ (G)": model.total_reflectance()[:, 1],
        "99.9 % energy radius [mm]": model.energy_radius(),
    }
    if model.kind == "exponential":
        a = -model.d[:, -1 if model.c.shape[1] == 1 else 1].mean(axis=1)  # (N, n): mean over directions
        for k in range(model.n_terms):
            maps[f"rate $-d_{k + 1}$ [1/mm] (G)"] = a[:, k]
        if model.colour == "shared":
            maps["$s_g$"], maps["$s_b$"] = model.s_g, model.s_b
    elif model.kind == "dipole":
        maps["$\\sigma_a$ (G) [1/mm]"] = model.sigma_a[:, 1]
        maps["$\\sigma_s'$ (G) [1/mm]"] = model.sigma_s_prime[:, 1]
    else:
        maps["A (G)"], maps["s (G) [1/mm]"] = model.A[:, 1], model.s[:, 1]
    fig, axes = plt.subplots(1, len(maps), figsize=(3.4 * len(maps), 3.2), squeeze=False)
    for ax, (title, v) in zip(axes[0], maps.items()):
        sc = ax.scatter(x[:, 0], x[:, 1], c=v, s=10, marker="s", cmap="viridis")
        ax.set_aspect("equal")
        ax.set_title(title, fontsize=9)
        fig.colorbar(sc, ax=ax, shrink=0.8)
    fig.tight_layout()
    _save(fig, Path(path))


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
) -> dict:
    """Evaluate models on a planar data set and write the figures, JSON and HTML report.

    With ``truth`` (an independent acquisition of the same incident points: another seed, usually
    more photons) every figure and headline number is against the truth, and the in-sample errors
    (against the data the models were fitted to) stand beside them under ``in_sample``.

    Parameters
    ----------
    models : ReflectanceModel or sequence of them, or dict label -> model
        The first is the primary model (its numbers are also the JSON's top level).
    dataset : PlanarDataset or path
    out_dir : path
        Report directory.
    points : list of int, optional
        Incident points for the profiles; default :func:`default_points`.
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

    Returns
    -------
    dict
        The JSON summary.
    """
    ds = dataset if isinstance(dataset, PlanarDataset) else open_dataset(dataset)
    if not isinstance(models, dict):
        models = list(models) if isinstance(models, (list, tuple)) else [models]
        models = {model_label(m): m for m in models}
    flagged = flagged or {}
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    exclusion = exclusion or {}
    in_sample = {
        name: planar_errors(m, ds, flagged=flagged.get(name), exclusion_mm=exclusion.get(name))
        for name, m in models.items()
    }
    held_out = None
    if truth is not None:
        truth = truth if isinstance(truth, PlanarDataset) else open_dataset(truth)
        held_out = {
            name: planar_errors(m, truth, flagged=flagged.get(name), exclusion_mm=exclusion.get(name))
            for name, m in models.items()
        }
    errors = held_out or in_sample
    shown = truth or ds
    points = default_points(ds.n_points) if points is None else list(points)
    plot_profiles(models, shown, points, out_dir / "profiles.png")
    plot_error_maps(errors, ds["x_i"], out_dir / "error_maps.png")
    plot_alpha(models, out_dir / "alpha.png")
    first = next(iter(models))
    plot_parameters(models[first], out_dir / "params.png")
    per_model = {}
    for name, e in errors.items():
        per_model[name] = e.summary()
        fl = flagged.get(name)
        per_model[name]["flagged_points"] = [] if fl is None else np.flatnonzero(fl).tolist()
        per_model[name]["physics"] = check_physics(models[name]).summary()
        if held_out is not None:
            per_model[name]["in_sample"] = in_sample[name].summary()
    summary = {
        "written_by": f"translucency {__version__}",
        "dataset": str(ds.path),
        "truth": None if truth is None else str(truth.path),
        "evaluated_against": "truth (independent acquisition)" if truth is not None else "the fitted data",
        "model": first,
        **per_model[first],
        "bands_mm": {k: [lo, hi if np.isfinite(hi) else None] for k, (lo, hi) in BANDS.items()},
        "models": per_model,
        "profile_points": points,
        "definition": "rel_l2 = ||model - data||_2 / ||data||_2 "
        "over valid pairs (mask, finite, r >= one pixel), "
        "RGB summed; noise_floor = sqrt(sum variance)/||data||_2",
    }
    write_json(out_dir / "report.json", summary)
    if json_path is not None:
        write_json(json_path, summary)
    _write_html(out_dir / "index.html", ds, summary, extra or [])
    return summary


def _write_html(path: Path, ds: PlanarDataset, summary: dict, extra: list) -> None:
    rows = []
    for name, s in summary["models"].items():
        cells = "".join(
            f"<td>{100 * s[k]:.2f} %</td>" for k in ("rel_l2", "rel_l2_near", "rel_l2_mid", "rel_l2_far")
        )
        ph = s["physics"]
        unphysical = len(set(ph["over_albedo"]) | set(ph["beyond_object"]))
        inside = s.get("in_sample")
        beside = "" if inside is None else f"<td>{100 * inside['rel_l2']:.2f} %</td>"
        rows.append(
            f"<tr><th>{html.escape(name)}</th>{cells}{beside}"
            f"<td>{100 * s['energy_error']['total']:.2f} %</td>"
            f"<td>{len(s['flagged_points'])}</td>"
            f"<td>{unphysical} (max ρ {ph['max_total_reflectance']:.3g})</td></tr>"
        )
    held_out = summary.get("truth") is not None
    noise_label = "the truth's own noise" if held_out else "measurement noise alone"
    pad = "<td></td>" * (4 if held_out else 3)
    against = (
        f"an independent acquisition of the same points (<code>{html.escape(summary['truth'])}</code>)"
        if held_out
        else "the data the models were fitted to (in-sample: a model that fits noise scores well here)"
    )
    nf = next(iter(summary["models"].values()))["noise_floor"]
    noise = "".join(f"<td>{100 * nf[k]:.2f} %</td>" for k in ("all", "near", "mid", "far"))
    figures = "".join(
        f'<figure><img src="{html.escape(f)}"><figcaption>{html.escape(c)}</figcaption></figure>'
        for f, c in extra
    )
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>translucency report</title>
<style>body{{font-family:sans-serif;max-width:1400px;margin:auto}} table{{border-collapse:collapse}}
td,th{{border:1px solid #ccc;padding:4px 8px;text-align:right}} img{{max-width:100%}}</style></head><body>
<h1>Planar fit report</h1>\
<p>Data set: <code>{html.escape(str(ds.path))}</code> — {ds.n_points} incident points,
windows {ds.window[0]}×{ds.window[1]} px at {ds.pitch} mm.</p>
<h2>Relative L2 error</h2><p>Against {against}.</p>
<table><tr><th>model</th><th>all</th><th>near &lt; 1 mm</th><th>mid 1–4 mm</th>
<th>far &gt; 4 mm</th>{"<th>in-sample, all</th>" if held_out else ""}<th>total reflectance per point</th>
<th>flagged points</th><th>unphysical points (ρ &gt; 1 or r<sub>99.9</sub> beyond
the sample)</th></tr>{"".join(rows)}
<tr><th>{noise_label}</th>{noise}{pad}</tr></table>
<p>{html.escape(summary["definition"])}</p>
<div style="display:flex;gap:1em;flex-wrap:wrap"><figure style="flex:1 1 40%"><img src="profiles.png">
<figcaption>Figure 1 (left): ring-averaged profiles around chosen incident points \
(green channel).</figcaption></figure>
<figure style="flex:1 1 55%"><img src="error_maps.png">\
<figcaption>Figure 1 (right): relative error per outgoing pixel
and per incident point.</figcaption></figure></div>
<figure><img src="alpha.png"><figcaption>Modulation texture α.</figcaption></figure>
<figure><img src="params.png">\
<figcaption>Parameters of the first model over the incident points.</figcaption></figure>
{figures}
</body></html>
"""
    with atomic_path(path) as tmp:
        tmp.write_text(page)
