"""Checks at the library's boundary: a Python argument of the wrong kind is one line naming it."""

from __future__ import annotations

import inspect
import os
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError, check_option
from ..acquire import Volume, load_volume
from ..acquire.objects import make_pig
from ..fit import FitResult
from ..io.inputs import expect_input
from ..io.mesh import check_mesh_file, load_mesh
from ..io.model_file import load_model, read_header

#: the up axes a mesh file may have (turned to +z)
UP_AXES = ("z", "y", "x")


def as_path(name: str, value) -> Path:
    """``value`` as a Path, or one line naming the argument."""
    if not isinstance(value, (str, os.PathLike)):
        raise TranslucencyError(f"{name}: expected a path, got {type(value).__name__}")
    return Path(value)


def whole_number(name: str, value, lo: int = 1) -> int:
    """A whole number ≥ ``lo`` (bools refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TranslucencyError(f"{name}: expected a whole number, got {value!r}")
    return int(check_option(name, int(value), lo=lo))


def one_or_two(name: str, value, kind):
    """One number for both axes, or two."""
    values = np.atleast_1d(np.asarray(value, dtype=object))
    if values.ndim != 1 or len(values) not in (1, 2):
        raise TranslucencyError(f"{name}: expected one number or two (x, y), got {value!r}")
    return tuple(kind(v) for v in (values if len(values) == 2 else (values[0], values[0])))


def refuse_unknown(where: str, options: dict, stage) -> None:
    """Refuse keywords the stage function does not take, naming them."""
    known = set(inspect.signature(stage).parameters)
    unknown = sorted(set(options) - known)
    if unknown:
        raise TranslucencyError(f"{unknown[0]}: not an option of {where}")


def volume_of(name: str, value) -> Volume:
    """A :class:`Volume`, or one read from a ``.npz`` path."""
    if isinstance(value, Volume):
        return value
    if isinstance(value, (str, os.PathLike)):
        return load_volume(value)
    raise TranslucencyError(
        f"{name}: expected a Volume or the path of a .npz volume, got {type(value).__name__}"
    )


def model_and_record(name: str, model) -> tuple[object, dict]:
    """(model, the fit's record) of a Fitting, a FitResult, a model file or a model."""
    if isinstance(getattr(model, "result", None), FitResult):  # a Fitting (fit_model): its fit
        model = model.result
    if isinstance(model, FitResult):
        return model.model, {
            "flagged_points": np.flatnonzero(model.flagged).tolist(),
            "fit": model.options,
            "acquisition": model.acquisition,
        }
    if isinstance(model, (str, os.PathLike)):
        meta = read_header(model).get("meta", {})
        return load_model(model), meta if isinstance(meta, dict) else {}
    if not all(hasattr(model, a) for a in ("alpha", "n_points", "geometry")):
        raise TranslucencyError(
            f"{name}: expected a model, a FitResult or a model file, got {type(model).__name__}"
        )
    return model, {}


def slab_of(size, voxel_mm, g) -> tuple[tuple[float, ...], float, float]:
    """A generated slab's size (mm), voxel (mm) and anisotropy, checked."""
    size = tuple(float(check_option("size", v, lo=0, open_lo=True, hi=1e5)) for v in np.atleast_1d(size))
    if len(size) != 3:
        raise TranslucencyError(f"size: expected (width, height, thickness) in mm, got {size!r}")
    voxel_mm = float(check_option("voxel_mm", voxel_mm, lo=0, open_lo=True))
    check_option("voxel_mm", voxel_mm, hi=min(size))  # at least one voxel across the thinnest side
    return size, voxel_mm, float(check_option("g", g, lo=-1, hi=1, open_lo=True, open_hi=True))


def sample_of(sample) -> tuple[str | None, Volume | None, Path | None]:
    """(generator name, Volume, .npz path) of ``sample``: exactly one of them is not None."""
    if isinstance(sample, str) and Path(sample).suffix != ".npz":
        return sample, None, None
    if isinstance(sample, (str, os.PathLike)):
        path = Path(sample)
        expect_input(path, ("volume file",), "sample")  # a mesh, a data set, a model: named as such
        return None, None, path
    return None, volume_of("sample", sample), None


def mesh_file_of(mesh) -> Path | None:
    """The mesh file of ``mesh``, checked (a folder, a missing file or a data set named before the output is
    judged); None for a Trimesh or None (the procedural pig)."""
    if isinstance(mesh, (str, os.PathLike)):
        path = Path(mesh)
        expect_input(path, ("mesh file",), "mesh")
        return check_mesh_file(path, "mesh")
    if mesh is not None and not (hasattr(mesh, "vertices") and hasattr(mesh, "faces")):
        raise TranslucencyError(f"mesh: expected a trimesh.Trimesh or a mesh file, got {type(mesh).__name__}")
    return None


def object_of(mesh, path: Path | None, scale_mm: float, up: str):
    """The object: the mesh file at ``path`` read with ``scale_mm`` and ``up``, the Trimesh ``mesh``, or the
    procedural pig for None."""
    if path is not None:
        return load_mesh(path, scale_mm=scale_mm, up=up)
    return make_pig() if mesh is None else mesh
