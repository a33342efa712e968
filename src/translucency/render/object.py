"""The object of a per-vertex model: its mesh, its volume (for the reference) and its boundary η.

:func:`object_of_model` rebuilds the mesh of a model (from the model itself, or from its data set for
older files); :func:`volume_of_dataset` the filling of a mesh data set (generated, or a user's file);
:func:`boundary_eta` the index of the boundary it was acquired behind; :func:`check_light_outside` refuses
a light inside the object before any work.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from .._validate import TranslucencyError, plain
from ..acquire import load_volume
from ..acquire.mesh import filling_record, object_volume
from ..io.mesh_dataset import open_mesh_dataset


def object_from_dataset(path):
    """(mesh, header) of a mesh data set (:mod:`translucency.io.mesh_dataset`)."""
    ds = open_mesh_dataset(path)
    return ds.mesh(), ds.header


def object_of_model(model, header: dict):
    """(mesh, acquisition header) of a per-vertex model file: from the model itself when it carries its
    triangles (``model.faces``, ``meta["acquisition"]``), else from its data set (older files).

    Examples
    --------
    >>> from translucency.model import BurleyModel, VertexAlpha
    >>> corners = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 10.0]])  # mm
    >>> model = BurleyModel([[0.0, 0.0, 0.0]], [[0.8] * 3], [[2.0] * 3], VertexAlpha(np.ones(4), corners),
    ...                     frame=[np.eye(3)])
    >>> model.faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])  # a tetrahedron
    >>> mesh, acquisition = object_of_model(model, {"meta": {"acquisition": {"eta": 1.4}}})
    >>> round(float(mesh.volume), 3), bool(mesh.is_watertight), acquisition  # 10³ / 6 mm³
    (166.667, True, {'eta': 1.4})
    >>> model.faces = None  # an older file, its data set not recorded
    >>> object_of_model(model, {"meta": {}})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: model: holds no mesh and its data set (none recorded) ...
    """
    meta = header.get("meta", {})
    if model.faces is not None:
        mesh = trimesh.Trimesh(np.asarray(model.alpha.vertices), np.asarray(model.faces), process=False)
        return mesh, meta.get("acquisition", {})
    dataset = meta.get("dataset", "")
    if not dataset or not Path(dataset).exists():
        raise TranslucencyError(
            f"model: holds no mesh and its data set {dataset or '(none recorded)'} is gone; "
            "refit it with this version (models now carry their mesh)"
        )
    return object_from_dataset(dataset)


def volume_of_dataset(mesh, header):
    """The filling of a mesh data set: rebuilt from its description (a generated one), or read again from
    the user's file it was acquired from, if that file is still there unchanged (``header["filling"]``).

    Examples
    --------
    >>> box = trimesh.creation.box(extents=(10.0, 6.0, 4.0))
    >>> header = {"sample": {"generator": "homogeneous:marble", "seed": 0},
    ...           "request": {"volume_grid": {"voxel_mm": 1.0}}}
    >>> volume = volume_of_dataset(box, header)  # the mesh's bounding box in 1 mm voxels, (z, y, x)
    >>> volume.shape, volume.size_mm, volume.voxel_mm
    ((4, 6, 10), (10.0, 6.0, 4.0), 1.0)
    >>> volume_of_dataset(box, {"sample": {}})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: data set: its filling cannot be rebuilt (not generated ...
    """
    d = header.get("sample", {})
    if d.get("generator") == "file":
        record = header.get("filling")
        if not isinstance(record, dict) or "sha256" not in record:
            raise TranslucencyError(
                f"data set: acquired from the user's filling {d.get('path', '?')}, whose path and hash "
                "were not recorded (older data set); re-acquire it for a reference"
            )
        path = Path(record["path"])
        if not path.is_file():
            raise TranslucencyError(
                f"{path}: the filling this object was acquired from is gone; no reference"
            )
        if filling_record(path)["sha256"] != record["sha256"]:
            raise TranslucencyError(
                f"{path}: the filling changed since this object was acquired (SHA-256 differs); no reference"
            )
        return load_volume(path)
    if "generator" not in d or "voxel_mm" not in header.get("request", {}).get("volume_grid", {}):
        raise TranslucencyError("data set: its filling cannot be rebuilt (not generated here); no reference")
    grid = header["request"]["volume_grid"]
    return object_volume(
        d["generator"], mesh, grid["voxel_mm"], g=header.get("g", 0.0), seed=d.get("seed", 0)
    )


def check_light_outside(mesh, light) -> None:
    """Refuse, in one line, a point or spot light inside the closed ``mesh`` — before any work.

    The generalised winding number of the surface around the light's position (the solid angle of every
    triangle seen from there, Van Oosterom and Strackee's formula, summed over 4π) is 1 inside a
    closed surface and 0 outside, whatever the orientation of its triangles.
    """
    if light.distant:  # directional and environment lights come from outside
        return
    p = np.asarray(light.position, dtype=np.float64)
    a, b, c = (
        np.asarray(mesh.vertices, dtype=np.float64)[np.asarray(mesh.faces)[:, k]] - p for k in range(3)
    )
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    dot = lambda x, y: np.einsum("ij,ij->i", x, y)  # noqa: E731
    denom = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb
    winding = 2.0 * np.arctan2(det, denom).sum() / (4.0 * np.pi)
    if abs(winding) > 0.5:
        raise TranslucencyError(
            f"light: the {light.kind} light at "
            f"{plain(p)} mm is inside the object (bounds {plain(np.round(mesh.bounds[0], 1))} to "
            f"{plain(np.round(mesh.bounds[1], 1))} mm)"
        )


def boundary_eta(header) -> float:
    """η of a mesh data set's boundary: its header's ``boundary_eta`` — or, in data sets written before
    it was recorded, 1 when acquired index-matched, else the medium's η.

    Examples
    --------
    >>> boundary_eta({"eta": 1.4}), boundary_eta({"eta": 1.4, "request": {"index_matched": True}})
    (1.4, 1.0)
    >>> boundary_eta({"eta": 1.4, "boundary_eta": 1.0})
    1.0
    >>> boundary_eta({})  # none recorded: index-matched
    1.0
    """
    if "boundary_eta" in header:
        return float(header["boundary_eta"])
    return 1.0 if header.get("request", {}).get("index_matched", False) else float(header.get("eta", 1.0))
