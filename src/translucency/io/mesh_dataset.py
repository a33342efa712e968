"""Mesh data sets (format version 1): per-vertex R_d of a 3D object, a chunked Zarr v3 directory.

What :func:`translucency.acquire.mesh.acquire_mesh` writes and the per-vertex
fit and the renderer read.  Layout (P incident vertices of a mesh of V vertices
and F triangles)::

    /             group; attrs["translucency_mesh_dataset"] = header (below)
    vertices      (V, 3) float32   positions, mm
    faces         (F, 3) int32
    normals       (V, 3) float32   outward unit normals
    vertex_area   (V,) float32     the area A_v each vertex stands for, mm²
    incident      (P,) int32       vertex index of each incident point
    R_d           (P, V, 3) float32  per unit incident power, mm⁻²
    specular      (P, 3) float32   Fresnel reflection at entry (fraction of the power), not in R_d
    chunk_done    (n_chunks,) bool written last for each chunk of points: resume marker

Header (JSON): ``format`` = "translucency-mesh-dataset", ``version`` = 1,
``units``, ``n_points``, ``n_vertices``, ``photons``, ``seed``, ``eta``, ``g``,
``sample`` (the filling's description), ``software`` and ``request`` (the
arguments that define the data, compared on resume).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
import zarr
from zarr.codecs import BloscCodec

from .._validate import TranslucencyError
from .dataset import summary_of_store
from .outputs import reopen_or_clear

HEADER_KEY = "translucency_mesh_dataset"
FORMAT = "translucency-mesh-dataset"
VERSION = 1
_ARRAYS = ("vertices", "faces", "normals", "vertex_area", "incident", "R_d", "specular", "chunk_done")


@dataclass
class MeshDataset:
    """An opened mesh data set; arrays are read lazily from the Zarr group."""

    path: Path
    header: dict
    group: object

    @property
    def n_points(self) -> int:
        return int(self.header["n_points"])

    def __getitem__(self, key: str) -> np.ndarray:
        if key not in _ARRAYS:
            raise KeyError(key)
        return np.asarray(self.group[key][...])

    def complete(self) -> bool:
        return bool(np.all(self["chunk_done"]))

    def mesh(self) -> trimesh.Trimesh:
        """The object's surface (mm) as stored, vertices in their stored order."""
        return trimesh.Trimesh(self["vertices"].astype(np.float64), self["faces"], process=False)


def is_mesh_dataset(path) -> bool:
    """Whether ``path`` is a folder whose root Zarr metadata carries the mesh data set's header."""
    meta = Path(path) / "zarr.json"
    try:
        return meta.is_file() and isinstance(
            json.loads(meta.read_text()).get("attributes", {}).get(HEADER_KEY), dict
        )
    except (OSError, ValueError, AttributeError):
        return False


def open_mesh_dataset(path, *, writable: bool = False) -> MeshDataset:
    """Open a mesh data set and check its header and arrays; one-line errors name the fault."""
    path = Path(path)
    if not path.exists():
        raise TranslucencyError(f"{path}: no such mesh data set")
    try:
        group = zarr.open_group(str(path), mode="r+" if writable else "r")
        header = dict(group.attrs).get(HEADER_KEY)
    except Exception as exc:  # noqa: BLE001 — any decoding fault becomes one line
        raise TranslucencyError(f"{path}: not a readable Zarr data set ({type(exc).__name__})") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT or header.get("version") != VERSION:
        raise TranslucencyError(f"{path}: not a translucency mesh data set (v{VERSION})")
    for name in _ARRAYS:
        if name not in group:
            raise TranslucencyError(f"{path}: missing array {name!r}")
    return MeshDataset(path, header, group)


def create_mesh_dataset(
    path,
    header: dict,
    mesh,
    vertex_area: np.ndarray,
    incident: np.ndarray,
    *,
    chunk_points: int,
    overwrite: bool = False,
    inputs=(),
) -> MeshDataset:
    """Create (or reopen for resuming) a mesh data set at ``path``.

    A data set with the same ``header["request"]`` is reopened so that finished
    chunks are kept; one made with other arguments is replaced only with
    ``overwrite``; anything else is never touched
    (:func:`translucency.io.outputs.claim_output`).
    """
    path = Path(path)
    old = reopen_or_clear(
        path,
        "mesh data set",
        header["request"],
        lambda p: open_mesh_dataset(p, writable=True),
        overwrite=overwrite,
        inputs=inputs,
    )
    if old is not None:  # the same acquisition: resume
        return old
    P, V = len(incident), len(mesh.vertices)
    n_chunks = -(-P // chunk_points)
    root = zarr.create_group(
        str(path), attributes={HEADER_KEY: header}, overwrite=False
    )  # never clears a folder
    comp = BloscCodec(cname="zstd", clevel=5, shuffle="shuffle")
    for name, data in (
        ("vertices", mesh.vertices.astype(np.float32)),
        ("faces", mesh.faces.astype(np.int32)),
        ("normals", mesh.vertex_normals.astype(np.float32)),
        ("vertex_area", vertex_area.astype(np.float32)),
        ("incident", incident.astype(np.int32)),
    ):
        root.create_array(name, data=data, compressors=comp)
    root.create_array(
        "R_d", shape=(P, V, 3), dtype="float32", chunks=(chunk_points, V, 3), compressors=comp, fill_value=0
    )
    root.create_array("specular", shape=(P, 3), dtype="float32", chunks=(chunk_points, 3), fill_value=0)
    root.create_array("chunk_done", shape=(n_chunks,), dtype="bool", chunks=(1,), fill_value=False)
    return MeshDataset(path, header, root)


def describe_mesh(ds: MeshDataset) -> dict:
    """A JSON-friendly summary for ``translucency info``."""
    h = ds.header
    return summary_of_store(
        ds.path,
        h,
        ds["chunk_done"],
        mesh=f"{h['n_vertices']:,} vertices, {ds.group['faces'].shape[0]:,} faces",
        **{"index matched": h.get("request", {}).get("index_matched")},
    )
