"""A rig's table of laser positions: one :class:`Shot` a row (image files, position, power, exposures)."""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..._validate import TranslucencyError
from ..shared.hdr import HDR_SUFFIXES, LDR_SUFFIXES

IMAGE_SUFFIXES = HDR_SUFFIXES + LDR_SUFFIXES


@dataclass(frozen=True)
class Shot:
    """One laser position: its image file(s), where the laser is, its power and exposure time(s).

    Attributes
    ----------
    files : tuple of Path
        Its image(s): one HDR image, repeated frames, or a bracket of LDR exposures.
    position : (float, float)
        Where the laser is, in ``units``.
    units : {"mm", "px"}
        Sample millimetres or image pixels.
    power : float
        Laser power, W.
    exposures : tuple of float
        Exposure time(s), s: one, or one per file of a bracket.

    Examples
    --------
    A row of a table of laser positions: a bracket of two LDR exposures, the laser given in pixels:

    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> for name in ("a.png", "b.png"):
    ...     _ = (d / name).write_bytes(b"")
    >>> _ = (d / "pos.csv").write_text("file,u,v,exposure\\na.png;b.png,120,80,0.01;0.1\\n")
    >>> shot = read_positions(d / "pos.csv", d)[0]
    >>> [f.name for f in shot.files], shot.position, shot.units, shot.exposures, shot.power
    (['a.png', 'b.png'], (120.0, 80.0), 'px', (0.01, 0.1), 1.0)
    """

    files: tuple[Path, ...]
    position: tuple[float, float]
    units: str  # "mm" (sample) or "px" (image)
    power: float = 1.0
    exposures: tuple[float, ...] = (1.0,)


def _split(value, name, where) -> list[str]:
    if isinstance(value, list | tuple):
        return [str(v) for v in value]
    return [v.strip() for v in str(value).split(";") if v.strip()] if value not in (None, "") else []


def read_positions(path, folder) -> list[Shot]:
    """The laser positions of a rig: a CSV or JSON table.

    Columns (CSV header, or keys of each JSON object in a list, or under ``"points"``):
    ``x``, ``y`` (sample mm) **or** ``u``, ``v`` (image pixels); optional ``file`` (image file(s) in
    ``folder``, several separated by ``;`` — repeated frames, or a bracket when ``exposure`` lists one
    time per file), ``power`` (W, for normalisation; default 1), ``exposure`` (s; default 1).  Without a
    ``file`` column the images of ``folder`` are taken in sorted order, one per row.

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / "a.pfm").write_bytes(b"")
    >>> _ = (d / "pos.csv").write_text("file,x,y,power\\na.pfm,1.5,2.0,0.5\\n")
    >>> s = read_positions(d / "pos.csv", d)[0]
    >>> s.files[0].name, s.position, s.units, s.power
    ('a.pfm', (1.5, 2.0), 'mm', 0.5)
    """
    path, folder = Path(path), Path(folder)
    if not path.is_file():
        raise TranslucencyError(f"{path}: no such table of laser positions")
    if not folder.is_dir():
        raise TranslucencyError(f"{folder}: no such folder of images")
    rows = _read_rows(path)
    if not rows:
        raise TranslucencyError(f"{path}: no laser positions")
    keys = set(rows[0])
    units, cols = _position_columns(path, keys)
    names = _image_names(path, folder, rows, keys)
    return [
        _read_shot(r, files, folder, cols, units, f"{path}, row {i + 1}")
        for i, (r, files) in enumerate(zip(rows, names))
    ]


def _read_rows(path: Path) -> list[dict]:
    """The table's rows: a JSON list of objects (or one under ``"points"``), or CSV (keys lower-cased)."""
    try:
        if path.suffix.lower() == ".json":
            obj = json.loads(path.read_text())
            rows = obj.get("points") if isinstance(obj, dict) else obj
            if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
                raise TranslucencyError(f"{path}: expected a list of objects (or one under 'points')")
        else:
            with open(path, newline="") as f:
                rows = [{k.strip().lower(): v for k, v in r.items() if k} for r in csv.DictReader(f)]
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise TranslucencyError(f"{path}: not a readable table ({type(exc).__name__})") from None
    return rows


def _position_columns(path: Path, keys: set) -> tuple[str, tuple[str, str]]:
    """The position's units and columns: ``x``, ``y`` (mm) or ``u``, ``v`` (px)."""
    if {"x", "y"} <= keys:
        return "mm", ("x", "y")
    if {"u", "v"} <= keys:
        return "px", ("u", "v")
    raise TranslucencyError(f"{path}: needs columns x, y (mm) or u, v (pixels); has {sorted(keys)}")


def _image_names(path: Path, folder: Path, rows: list[dict], keys: set) -> list[list[str]]:
    """Each row's image file names: its ``file`` column, else the folder's images in sorted order."""
    if "file" in keys:
        return [_split(r.get("file"), "file", path) for r in rows]
    found = sorted(p.name for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    if len(found) != len(rows):
        raise TranslucencyError(
            f"{path}: {len(rows)} laser positions but {len(found)} images in {folder}; "
            "the counts must match (or name each row's image in a 'file' column)"
        )
    return [[n] for n in found]


def _read_shot(r: dict, files: list[str], folder: Path, cols, units: str, where: str) -> Shot:
    """One row as a :class:`Shot`: its position, power (W) and exposures (s) checked, its images found."""
    try:
        pos = tuple(float(r[c]) for c in cols)
        power = float(r.get("power") or 1.0)
        times = [float(t) for t in _split(r.get("exposure"), "exposure", where)] or [1.0]
    except (TypeError, ValueError):
        raise TranslucencyError(f"{where}: position, power and exposure must be numbers") from None
    if not files:
        raise TranslucencyError(f"{where}: no image file named")
    if not np.all(np.isfinite(pos)):
        raise TranslucencyError(f"{where}: position {pos} is not finite")
    if not (np.isfinite(power) and power > 0):
        raise TranslucencyError(f"{where}: power must be > 0 W, got {power}")
    if not all(np.isfinite(t) and t > 0 for t in times):
        raise TranslucencyError(f"{where}: exposure times must be > 0 s, got {times}")
    if len(times) not in (1, len(files)):
        raise TranslucencyError(f"{where}: {len(files)} images but {len(times)} exposure times")
    paths = _image_paths(folder, files, where)
    if all(p.suffix.lower() in LDR_SUFFIXES for p in paths) and len(paths) > 1 and len(times) != len(paths):
        raise TranslucencyError(f"{where}: a bracket of {len(paths)} LDR images needs as many exposures")
    return Shot(paths, pos, units, power, tuple(times))


def _image_paths(folder: Path, files: list[str], where: str) -> tuple[Path, ...]:
    """A row's images in ``folder``: each present and an image, all HDR or all LDR."""
    paths = tuple(folder / n for n in files)
    for p in paths:
        if not p.is_file():
            raise TranslucencyError(f"{where}: image {p} is missing")
        if p.suffix.lower() not in IMAGE_SUFFIXES:
            raise TranslucencyError(f"{where}: {p.name} is not an image ({', '.join(IMAGE_SUFFIXES)})")
    ldr = [p.suffix.lower() in LDR_SUFFIXES for p in paths]
    if any(ldr) and not all(ldr):
        raise TranslucencyError(f"{where}: mixes HDR and LDR images")
    return paths
