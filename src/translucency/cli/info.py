"""``translucency info``: what a model file or a data set holds, its size on disk, whether it is valid.

One record per path (:func:`translucency.workflow.inspecting.describe`, JSON-ready, its schema in
docs/json.md, written by docs/_gen/json_schemas.py) and its display as a table (:func:`_rows`): ``--json``
prints the record, numbers as numbers, nothing cut.
"""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.table import Table

from ._common import PANEL_RUN, console, jsonable, user_errors


@user_errors
def info(
    path: Path = typer.Argument(..., help="A model file (.model.zip) or a data set (.zarr directory)."),
    as_json: bool = typer.Option(
        False, "--json", help="Print the fields as one JSON object (for scripts).", rich_help_panel=PANEL_RUN
    ),
):
    """Describe a model file or a data set: what it holds, its size on disk, whether it is valid."""
    from ..workflow.inspecting import describe  # Zarr and NumPy: what reading the file needs

    fields = describe(path)
    if as_json:
        print(json.dumps(jsonable(fields), allow_nan=False, indent=2))  # plain: no wrapping
    else:
        table = Table(title=str(path), show_header=False)
        for key, value in _rows(fields):
            table.add_row(f"[bold]{key}[/]", value, style="red" if value.startswith("no") else None)
        console.print(table)
    if fields["what"] == "model" and not fields["valid"]:
        raise typer.Exit(1)


def _mm(v) -> str:
    return ", ".join(f"{x:.4g}" for x in v)


def _rows(fields: dict):
    """(label, text) rows of the table a person reads; the record keeps every value in full."""
    size = fields["size_bytes"]
    size_text = f"{size:,} bytes ({size / 1e6:.3f} MB)"
    if "bounds_mm" in fields:
        lo, hi = fields["bounds_mm"]
        bounds = [
            (
                "bounds",
                f"x {lo[0]:.4g} … {hi[0]:.4g}, y {lo[1]:.4g} … {hi[1]:.4g}, z {lo[2]:.4g} … {hi[2]:.4g} mm",
            ),
            ("centre", f"{_mm(fields['centre_mm'])} mm"),
        ]
    else:
        bounds = []
    if fields["what"] != "model":
        return _dataset_rows(fields, size_text, bounds)
    return _model_rows(fields, size_text, bounds)


def _dataset_rows(fields: dict, size_text: str, bounds: list):
    """The rows of a planar or a mesh data set."""
    damaged = fields["damaged"]
    rows = [
        ("format", f"{fields['format']} v{fields['version']}"),
        ("incident points", str(fields["n_points"])),
    ]
    if fields["what"] == "planar data set":
        h, w = fields["window_px"]
        rows += [("window", f"{h} x {w} px at {fields['pitch_mm']} mm"), ("dtype", fields["dtype"])]
    else:
        rows += [
            ("mesh", f"{fields['n_vertices']:,} vertices, {fields['n_faces']:,} faces"),
            *bounds,
            ("index matched", str(fields["index_matched"])),
        ]
        if fields.get("reentry") is not None:
            rows.append(("re-entry", f"{fields['reentry']} (light through the air from part to part)"))
        if fields.get("unscattered") is not None:
            share = " / ".join(f"{v:.4f}" for v in fields["unscattered"])
            rows.append(("unscattered", f"{share} of a beam (R, G, B), kept apart from R_d"))
        inc = fields.get("incidence") or {}
        if inc.get("directions", 1) > 1:
            angles = ", ".join(f"{t:g}" for t in inc["polar_deg"])
            rows.append(("incidence", f"normal + {angles} deg x {inc['azimuths']} azimuths"))
        if fields.get("exit_bins"):
            rows.append(("exit bins", f"{fields['exit_bins']} (polar x azimuthal sectors from away)"))
        if fields.get("source") == "photographs":
            rows += [
                (
                    "source",
                    f"photographs, {len(fields['cameras'])} cameras, exit law {fields['exit_law']}",
                ),
            ]
    rows += [
        (
            "damaged",
            ", ".join(f"{k} chunks {v}" for k, v in damaged.items())
            or "none (every finished chunk present and decodable)",
        ),
        ("sample", _short(fields["sample"])),
        (
            "photons per point",
            f"{fields['photons']:,.0f} (equivalent: the measured noise)"
            if fields.get("source") == "photographs"
            else str(fields["photons"]),
        ),
        ("seed", str(fields["seed"])),
        ("complete", f"{fields['chunks_done']}/{fields['chunks']} chunks"),
        ("size on disk", size_text),
        ("software", json.dumps(fields["software"])),
    ]
    return rows


def _model_rows(fields: dict, size_text: str, bounds: list):
    """The rows of a model file."""
    from ..workflow.inspecting import MODEL_FIELDS  # loaded by the command already (describe)

    rows = [("size on disk", size_text)]
    rows += [(key, str(fields[key])) for key in (*MODEL_FIELDS, "dtype") if key in fields]
    if fields["meta"]:
        rows.append(("meta", _short(fields["meta"])))
    chosen = ((fields["meta"] or {}).get("fit") or {}).get("structure")
    if isinstance(chosen, dict) and chosen.get("summary"):  # the fit's held-out choice
        rows.append(("structure", str(chosen["summary"])))
    if not fields["intact"]:
        return [*rows, ("valid", f"no — {fields['problem']}")]
    alpha = fields["alpha"]
    checks = "shapes, dtypes, finiteness, eq. (2), checksum, physical bounds"
    rows += [
        ("valid", f"yes ({checks})" if fields["valid"] else f"no — {fields['problem']}"),
        ("physical", fields["physical"]["description"]),
        (
            "alpha",
            "shape {}, range [{:.3g}, {:.3g}]".format(tuple(alpha["shape"]), alpha["min"], alpha["max"]),
        ),
        ("total R_d (R,G,B)", "mean " + " ".join(f"{v:.4g}" for v in fields["total_reflectance_mean"])),
        (
            "beyond the object",
            "no edge (a semi-infinite slab)"
            if fields["object_size_mm"] is None
            else f"up to {100 * fields['beyond_object_max']:.2g}% of a point's energy "
            f"(bound {100 * fields['beyond_object_bound']:.0f}%)",
        ),
        (
            "99.9% energy radius",
            f"{fields['energy_radius_mm']['min']:.3g} … {fields['energy_radius_mm']['max']:.3g} mm "
            f"(on {fields['object']})",
        ),
        *bounds,
    ]
    if fields["measured"]:
        has_table = "through" in fields["measured"]
        table = " (the through-body table: render draws it, --paper not)" if has_table else ""
        rows.append(("measured", ", ".join(fields["measured"]) + table))
    if fields.get("medium"):
        rows += _medium_rows(fields["medium"])
    return rows


def _medium_rows(medium: dict):
    """The medium estimated from the scan: per channel min / median / max over the incident points."""
    over = f"(min / median / max over {medium['points']} points)"
    rows = []
    for key, label, unit in (
        ("sigma_s", "σ_s", " mm⁻¹"),
        ("sigma_a", "σ_a", " mm⁻¹"),
        ("albedo", "albedo", ""),
    ):
        ranges = ", ".join(
            f"{name} " + " / ".join(f"{v:.4g}" for v in channel) for name, channel in zip("RGB", medium[key])
        )
        rows.append((f"medium {label}", f"{ranges}{unit} {over}"))
    rows.append(("medium", f"estimated from the scan alone: {medium['assumed']}"))
    return rows


def _short(value: dict, limit: int = 300) -> str:
    """A nested record in one line for the table, cut at a whole entry (``--json`` shows all of it)."""
    parts, used = [], 0
    for key, v in value.items():
        text = f"{key}={json.dumps(jsonable(v))}"
        if used + len(text) > limit and parts:
            parts.append("… (--json shows all)")
            break
        parts.append(text)
        used += len(text) + 2
    return ", ".join(parts)
