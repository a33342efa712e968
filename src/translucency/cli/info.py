"""``translucency info``: what a model file or a data set holds, its size on disk, whether it is valid."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import typer
from rich.table import Table

from ..io.dataset import describe, open_dataset
from ..io.mesh_dataset import describe_mesh, is_mesh_dataset, open_mesh_dataset
from ..io.model_file import ModelFileError, load_model, read_header
from ..model import check_physics
from ._common import console, user_errors


@user_errors
def info(
    path: Path = typer.Argument(..., help="A model file (.model.zip) or a data set (.zarr directory)."),
    as_json: bool = typer.Option(False, "--json", help="Print the fields as one JSON object (for scripts)."),
):
    """Describe a model file or a data set: what it holds, its size on disk, whether it is valid."""
    if path.is_dir():
        ds = open_mesh_dataset(path) if is_mesh_dataset(path) else open_dataset(path)
        _show(path, describe_mesh(ds) if is_mesh_dataset(path) else describe(ds), as_json)
        return
    fields, ok = _info_model(path)
    _show(path, fields, as_json)
    if not ok:
        raise typer.Exit(1)


def _show(path: Path, fields: dict, as_json: bool) -> None:
    """The fields of ``info`` as a table, or as one JSON object on stdout."""
    if as_json:
        print(json.dumps({"path": str(path), **fields}, default=str, indent=2))  # plain: no wrapping
        return
    table = Table(title=str(path), show_header=False)
    for key, value in fields.items():
        table.add_row(f"[bold]{key}[/]", str(value), style="red" if str(value).startswith("no") else None)
    console.print(table)


def _info_model(path: Path) -> tuple[dict, bool]:
    """``info``'s fields of a model file, and whether it is valid (intact and physical)."""
    size = path.stat().st_size if path.exists() else 0
    header = read_header(path)  # a ModelFileError is a TranslucencyError: one line, exit 2
    fields = {"size on disk": f"{size:,} bytes ({size / 1e6:.3f} MB)"}
    for key in (
        "format",
        "version",
        "kind",
        "geometry",
        "n_points",
        "n_terms",
        "n_directions",
        "colour",
        "dtype",
    ):
        if key in header:
            fields[key] = header[key]
    if header.get("meta"):
        fields["meta"] = ", ".join(f"{k}={v}" for k, v in header["meta"].items())[:300]
    try:
        model = load_model(path)
    except ModelFileError as exc:
        fields["valid"] = f"no — {exc}"
        return fields, False
    physics = check_physics(model)
    fields["valid"] = (
        "yes (shapes, dtypes, finiteness, eq. (2), checksum, physical bounds)"
        if physics.ok
        else "no — the file is intact, but the model is not physical"
    )
    fields["physical"] = physics.describe()
    values = model.alpha.values
    fields["alpha"] = f"shape {model.alpha.shape}, range [{values.min():.3g}, {values.max():.3g}]"
    fields["total R_d (R,G,B)"] = "mean " + " ".join(f"{v:.4g}" for v in physics.total.mean(axis=0))
    fields["99.9% energy radius"] = (
        f"{np.min(physics.radius):.3g} … {np.max(physics.radius):.3g} mm (object {physics.size_mm:.3g} mm)"
    )
    return fields, physics.ok
