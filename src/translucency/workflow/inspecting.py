"""Inspection as functions: what a model file or a data set holds (:func:`describe`), and the measured
materials of Jensen et al. 2001 with the dipole's total reflectance (:func:`describe_materials`).

``translucency info`` and ``translucency materials`` print these records.  Cheap by design: reading a
file needs Zarr and NumPy, never Mitsuba, Dask or Matplotlib (the command's start-up).  Units: mm, σ in
mm⁻¹, R_d in mm⁻².
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError, check_option
from ..geometry import object_bounds
from ..io.dataset import describe as describe_planar
from ..io.dataset import open_dataset
from ..io.inputs import expect_input
from ..io.mesh_dataset import describe_mesh, is_mesh_dataset, open_mesh_dataset
from ..io.model_file import ModelFileError, load_model, read_header
from ..model import MATERIALS, check_physics, dipole_total_reflectance

__all__ = ["MODEL_FIELDS", "describe", "describe_materials"]

#: the header fields of a model file that a description lists, in order
MODEL_FIELDS = ("format", "version", "kind", "geometry", "n_points", "n_terms", "n_directions", "colour")
#: what the medium estimated from the scan assumes (medium/estimate.py), stated beside its numbers
MEDIUM_ASSUMED = (
    "g = 0 assumed (similar medium), index-matched"  # = medium.estimate.ASSUMED (a test holds them equal)
)


def describe(path) -> dict:
    """What a model file or a data set holds, its size on disk, whether it is valid.

    ``translucency info PATH`` prints this record (``--json``: as it is; its schema in docs/json.md).

    Parameters
    ----------
    path : str or Path
        A model file (``.model.zip``), a planar or a mesh data set (``.zarr`` folder).

    Returns
    -------
    dict
        ``command``, ``path``, ``what`` (``"model"``, ``"planar data set"`` or ``"mesh data set"``) and
        the fields of that kind: for a model its header, ``valid``, ``intact``, ``problem``, ``physical``,
        ``alpha``'s range, energy radii; for a data set its header, ``damaged`` chunks, ``chunks_done``.

    Raises
    ------
    TranslucencyError
        No such path, or not a model file nor a data set.  A damaged model file is described
        (``valid: False`` with its ``problem``), not refused.

    Examples
    --------
    >>> from translucency import describe
    >>> import translucency as tl
    >>> record = describe(tl.data.default_dataset_path())
    >>> record["what"], record["n_points"], record["chunks_done"] == record["chunks"]
    ('planar data set', 1024, True)
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TranslucencyError(f"path: expected a path, got {type(path).__name__}")
    path = Path(path)
    expect_input(path, ("model file", "planar data set", "mesh data set"))
    if path.is_dir():
        if is_mesh_dataset(path):
            return {
                "command": "info",
                "path": path,
                "what": "mesh data set",
                **describe_mesh(open_mesh_dataset(path)),
            }
        return {
            "command": "info",
            "path": path,
            "what": "planar data set",
            **describe_planar(open_dataset(path)),
        }
    return {"command": "info", "path": path, "what": "model", **_model_record(path)}


def _model_record(path: Path) -> dict:
    """The record of a model file: its header, whether it is intact and physical, its ranges."""
    header = read_header(path)  # a ModelFileError is a TranslucencyError: one line, exit 2
    fields = {"size_bytes": path.stat().st_size}
    fields.update({key: header[key] for key in (*MODEL_FIELDS, "dtype") if key in header})
    fields["meta"] = header.get("meta") or {}
    try:
        model = load_model(path)
    except ModelFileError as exc:
        return {**fields, "valid": False, "intact": False, "problem": str(exc)}
    physics = check_physics(model)
    values = model.alpha.values
    fields.update(
        valid=bool(physics.ok),
        intact=True,
        problem=None if physics.ok else "the file is intact, but the model is not physical",
        physical={"ok": bool(physics.ok), "description": physics.describe(), **physics.summary()},
        alpha={"shape": list(model.alpha.shape), "min": float(values.min()), "max": float(values.max())},
        total_reflectance_mean=physics.total.mean(axis=0).tolist(),
        energy_radius_mm={"min": float(np.min(physics.radius)), "max": float(np.max(physics.radius))},
        object_size_mm=float(physics.size_mm) if np.isfinite(physics.size_mm) else None,
        object=physics.summary()["object"],
        beyond_object_max=float(np.max(physics.beyond)) if len(physics.beyond) else 0.0,
        beyond_object_bound=float(physics.beyond_bound),
        # what the model carries beside the paper's parameters (the renderer's measured near field, the
        # through-body table of model/through.py)
        measured=sorted((model.measured or {}).keys()),
    )
    if model.geometry == "mesh":
        fields.update(object_bounds(model.alpha.vertices))
    medium = _medium_record(model)
    if medium is not None:  # (a model without the estimate: no field)
        fields["medium"] = medium
    return fields


def _medium_record(model) -> dict | None:
    """The medium estimated from the scan (``measured/medium``, :mod:`translucency.medium.estimate`): per
    channel (R, G, B) the [min, median, max] over the incident points of σ_s and σ_a (mm⁻¹) and the
    albedo, and what the estimate assumes; None for a model without one."""
    if "medium" not in (model.measured or {}):
        return None
    from ..medium.estimate import medium_of  # info of a model without a medium loads none of it

    return medium_of(model).summary()


def describe_materials(eta: float = 1.3) -> dict:
    """Jensen et al. 2001's measured coefficients and the dipole's total reflectance of each material.

    ``translucency materials --eta ETA`` prints this record (as a table, or ``--json``).

    Parameters
    ----------
    eta : float
        Relative index of refraction of the dipole's boundary (> 0).

    Returns
    -------
    dict
        ``command``, ``eta`` and ``materials``: name → ``sigma_s_prime``, ``sigma_a`` (mm⁻¹, R G B),
        ``R_d_dipole`` (the dipole's total reflectance at ``eta``) and ``R_d_published``.

    Raises
    ------
    TranslucencyError
        ``eta`` not a finite number > 0.

    Examples
    --------
    >>> from translucency import describe_materials
    >>> record = describe_materials(1.3)
    >>> "marble" in record["materials"], len(record["materials"]["marble"]["R_d_dipole"])
    (True, 3)
    """
    check_option("eta", eta, lo=0, open_lo=True)
    rows = {}
    for name, m in MATERIALS.items():
        rows[name] = {
            "sigma_s_prime": m.sigma_s_prime,
            "sigma_a": m.sigma_a,
            "R_d_dipole": dipole_total_reflectance(m.sigma_a, m.sigma_s_prime, eta),
            "R_d_published": m.R_d_published,
        }
    return {"command": "materials", "eta": eta, "materials": rows}
