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
    unscattered   (P, 3) float32   the fraction that left without scattering, not in R_d (request
                                   ``unscattered`` = "apart"; absent where it was counted in R_d)
    chunk_done    (n_chunks,) bool written last for each chunk of points: resume marker

A data set measured from photographs (``translucency import object``, header ``source`` =
"photographs") also holds, chunked as R_d::

    R_d_var       (P, V, 3) float32  the variance of each R_d, mm⁻⁴
    flags         (P, V) uint8     why a pair was not measured (bits: 1 unseen and filled from its
                                   neighbours, 2 saturated, 4 grazing, 8 inside the laser's spot);
                                   the per-vertex fit leaves flagged pairs out

A tally with angle axes (:mod:`translucency.angles`; header ``angles``) also holds, for D = the
incidence's directions (the normal first) and B exit bins::

    R_d_oblique       (P, D-1, V, 3) float32  R_d of the oblique beams (header angles.incidence)
    specular_oblique  (P, D-1, 3) float32     their Fresnel reflection at entry
    exit_bins         (P, D, V, 3, B) float32 the part of each R_d (normal, then oblique) that left
                                              through each exit bin (header angles.exit_bins)

A data set without them (every one made before they existed) reads as the normal beam only, without
exit bins (:attr:`MeshDataset.incidence`, :attr:`MeshDataset.exit_bins`).

Header (JSON): ``format`` = "translucency-mesh-dataset", ``version`` = 1,
``units``, ``n_points``, ``n_vertices``, ``photons``, ``seed``, ``eta``, ``g``,
``sample`` (the filling's description), ``software`` and ``request`` (the
arguments that define the data, compared on resume); for a user's filling file
(``acquire mesh --volume``) also ``filling`` = {``path`` (absolute), ``sha256``}, so
that the reference of a model fitted to it can be rendered while the file is unchanged.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._validate import TranslucencyError
from .._version import __version__
from ..angles import AngleAxes, angle_arrays
from ..geometry import object_bounds, tangent_frames
from ._store import ChunkedStore, check_shapes, open_store
from .outputs import kind_of, reopen_or_clear

if TYPE_CHECKING:  # the annotations only: trimesh loads where a mesh is built
    import trimesh

HEADER_KEY = "translucency_mesh_dataset"
FORMAT = "translucency-mesh-dataset"
VERSION = 1
_SURFACE = ("vertices", "faces", "normals", "vertex_area", "incident")
_ARRAYS = ("vertices", "faces", "normals", "vertex_area", "incident", "R_d", "specular", "chunk_done")
_ANGLES = ("R_d_oblique", "specular_oblique", "exit_bins")  # present where the header announces them
_APART = ("unscattered",)  # present where the request says the unscattered light was kept apart


class MeshDataset(AngleAxes, ChunkedStore):
    """An opened mesh data set; arrays are read lazily from the Zarr group.

    For every finished chunk of points :meth:`damaged_chunks` looks for the ``R_d`` file (every chunk
    written is a file: ``write_empty_chunks``) and (``decode``) decodes ``R_d`` and ``specular``; the
    arrays of the surface (vertices, faces, normals, areas, incident vertices) are listed as chunk 0
    when they are missing or do not decode.
    """

    KIND = "mesh data set"
    HEADER_KEY = HEADER_KEY
    FORMAT = FORMAT
    VERSION = VERSION
    ARRAYS = (*_ARRAYS, *_APART, *_ANGLES)

    @property
    def PER_POINT(self) -> tuple[str, ...]:  # noqa: N802 — the store's name for it
        return ("R_d", "specular", *(name for name in (*_APART, *_ANGLES) if name in self.group))

    @classmethod
    def from_group(cls, path: Path, header: dict, group) -> MeshDataset:
        P, V = header.get("n_points"), header.get("n_vertices")
        if not (isinstance(P, int) and isinstance(V, int) and P >= 1 and V >= 3):
            raise TranslucencyError(f"{path}: header n_points {P!r} / n_vertices {V!r} are not valid counts")
        check_shapes(
            path,
            group,
            {
                "vertices": (V, 3),
                "faces": (None, 3),
                "normals": (V, 3),
                "vertex_area": (V,),
                "incident": (P,),
                "R_d": (P, V, 3),
                "specular": (P, 3),
                "chunk_done": (None,),
            },
        )
        announced = angle_arrays(header.get("angles"), P, (V,))
        measured = [("R_d_var", (P, V, 3)), ("flags", (P, V)), ("unscattered", (P, 3))]  # (optional)
        for name, shape in [*measured, *announced]:
            if name in group and tuple(group[name].shape) != shape:
                raise TranslucencyError(
                    f"{path}: array {name!r} has shape {tuple(group[name].shape)}, expected {shape}"
                )
        for name, _ in announced:  # the angle axes the header announces
            if name not in group:
                raise TranslucencyError(f"{path}: header has angles but array {name!r} is missing")
        k = int(group["R_d"].chunks[0])
        if group["chunk_done"].shape[0] != -(-P // k):
            raise TranslucencyError(f"{path}: array 'chunk_done' does not match {P} points in chunks of {k}")
        return cls(path, header, group)

    @property
    def chunk_points(self) -> int:
        return int(self.group["R_d"].chunks[0])

    def incident_frames(self) -> np.ndarray:
        """(P, 3, 3) tangent frames (t, b, n) of the incident points, in which :attr:`incidence`'s
        directions are given (:func:`translucency.geometry.tangent_frames` of the stored normals)."""
        normals = np.asarray(self.group["normals"][...], dtype=np.float64)
        return tangent_frames(normals[np.asarray(self.group["incident"][...])])

    def R_d_toward(self, d: int, points=slice(None)) -> np.ndarray:
        """R_d (P, V, 3) of the beams from direction ``d`` of :attr:`incidence` (0: the normal)."""
        if not 0 <= d < self.incidence.count:
            raise TranslucencyError(f"{self.path}: direction {d} not in 0..{self.incidence.count - 1}")
        if d == 0:
            return np.asarray(self.group["R_d"][points])
        return np.asarray(self.group["R_d_oblique"][points, d - 1])

    def _expects_files(self, name: str) -> bool:
        return name in ("R_d", *_ANGLES)  # written with every chunk a file: a missing one is damage

    def _damaged_whole(self, decode: bool) -> dict:
        bad: dict = {}
        for name in _SURFACE:
            arr = self.group[name]
            files = [f for f in (self.path / name / "c").rglob("*") if f.is_file()]
            if len(files) < arr.nchunks:
                bad[name] = [0]
            elif decode:
                try:
                    arr[...]
                except Exception:  # noqa: BLE001 — a chunk that does not decode is damaged
                    bad[name] = [0]
        return bad

    def mesh(self) -> trimesh.Trimesh:
        """The object's surface (mm) as stored, vertices in their stored order."""
        import trimesh  # heavy: trimesh loads only where the surface is used (not for info or a fit)

        return trimesh.Trimesh(self["vertices"].astype(np.float64), self["faces"], process=False)


def is_mesh_dataset(path) -> bool:
    """Whether ``path`` is a folder whose root Zarr metadata carries the mesh data set's header."""
    return kind_of(path) == MeshDataset.KIND


def open_mesh_dataset(path, *, writable: bool = False) -> MeshDataset:
    """Open a mesh data set and check its header and arrays; one-line errors name the fault
    (:func:`~translucency.io._store.open_store`)."""
    return open_store(path, (MeshDataset,), writable=writable)


def mesh_header(
    *, n_points: int, n_vertices: int, photons: int, seed: int, eta, g, sample, request, **more
) -> dict:
    """The header every mesh data set opens with (module notes), whoever wrote it — a photon tally
    (``acquire mesh``) or photographs (``import object``) — with ``more`` fields after it.  ``eta``,
    ``g``: the medium's index and mean cosine; ``sample``: its description; ``request``: what makes a
    rerun resume (JSON)."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "units": {"length": "mm", "R_d": "mm^-2"},
        "n_points": int(n_points),
        "n_vertices": int(n_vertices),
        "photons": int(photons),
        "seed": int(seed),
        "eta": float(eta),
        "g": float(g),
        "sample": sample,
        "software": {"translucency": __version__},
        "request": request,
        **more,
    }


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
    measured: bool = False,
) -> MeshDataset:
    """Create (or reopen for resuming) a mesh data set at ``path``.

    A data set with the same ``header["request"]`` is reopened so that finished
    chunks are kept; one made with other arguments is replaced only with
    ``overwrite``; anything else is never touched
    (:func:`translucency.io.outputs.claim_output`).  ``measured``: also the arrays of a data set measured
    from photographs, ``R_d_var`` and ``flags`` (module notes).
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
    surface = _surface_arrays(mesh, vertex_area, incident)
    if old is not None:  # the same acquisition: resume, and redo what is damaged
        return _redo_damaged(old, path, surface)
    import zarr  # heavy: Zarr loads where a store is read or written, not for --help
    from zarr.codecs import BloscCodec

    root = zarr.create_group(
        str(path), attributes={HEADER_KEY: header}, overwrite=False
    )  # never clears a folder
    comp = BloscCodec(cname="zstd", clevel=5, shuffle="shuffle")
    for name, data in surface.items():
        root.create_array(name, data=data, compressors=comp, config={"write_empty_chunks": True})
    _create_per_point(root, header, len(incident), len(mesh.vertices), chunk_points, comp, measured)
    return MeshDataset(path, header, root)


def _surface_arrays(mesh, vertex_area: np.ndarray, incident: np.ndarray) -> dict:
    """The arrays written whole at creation: vertices (mm), faces, normals, vertex areas (mm²), incident."""
    return {
        "vertices": mesh.vertices.astype(np.float32),
        "faces": mesh.faces.astype(np.int32),
        "normals": mesh.vertex_normals.astype(np.float32),
        "vertex_area": vertex_area.astype(np.float32),
        "incident": incident.astype(np.int32),
    }


def _redo_damaged(old: MeshDataset, path: Path, surface: dict) -> MeshDataset:
    """A reopened data set with its damaged surface arrays rewritten and damaged chunks marked not done."""
    damaged = old.damaged_chunks()
    for name in _SURFACE:
        if name in damaged:  # written whole at creation: write it again
            old.group[name].with_config({"write_empty_chunks": True})[...] = surface[name]
    chunks = sorted({chunk for name in (*old.PER_POINT, "chunk_done") for chunk in damaged.get(name, [])})
    for chunk in chunks:
        old.group["chunk_done"][chunk] = False
    if damaged:
        warnings.warn(
            f"{path}: {', '.join(f'{k} chunks {v}' for k, v in damaged.items())} were missing or "
            "damaged; acquiring them again",
            stacklevel=3,  # (the caller of create_mesh_dataset)
        )
    return old


def _create_per_point(root, header: dict, P: int, V: int, chunk_points: int, comp, measured: bool) -> None:
    """The arrays filled point by point (chunked by ``chunk_points``), zero, and the chunks' done flags."""
    every = {"write_empty_chunks": True}  # every written chunk is a file: a missing one is damage
    for name in ("R_d", "R_d_var") if measured else ("R_d",):  # (P, V, 3), chunked by points
        root.create_array(
            name,
            shape=(P, V, 3),
            dtype="float32",
            chunks=(chunk_points, V, 3),
            compressors=comp,
            fill_value=0,
            config=every,
        )
    root.create_array(
        "specular", shape=(P, 3), dtype="float32", chunks=(chunk_points, 3), fill_value=0, config=every
    )
    if (header.get("request") or {}).get("unscattered") == "apart":
        root.create_array(
            "unscattered", shape=(P, 3), dtype="float32", chunks=(chunk_points, 3), fill_value=0, config=every
        )
    if measured:
        root.create_array(
            "flags",
            shape=(P, V),
            dtype="uint8",
            chunks=(chunk_points, V),
            compressors=comp,
            fill_value=0,
            config=every,
        )
    for name, shape in angle_arrays(header.get("angles"), P, (V,)):  # by points, one direction a chunk
        root.create_array(
            name,
            shape=shape,
            dtype="float32",
            chunks=(chunk_points, 1, *shape[2:]),
            compressors=comp,
            fill_value=0,
            config=every,
        )
    n_chunks = -(-P // chunk_points)
    root.create_array("chunk_done", shape=(n_chunks,), dtype="bool", chunks=(1,), fill_value=False)


def describe_mesh(ds: MeshDataset) -> dict:
    """What ``translucency info`` reports of a mesh data set (JSON-ready: docs/json.md), with the object's
    bounds and centre in mm (where a light or a camera goes)."""
    h = ds.header
    vertices = np.asarray(ds.group["vertices"][...], dtype=np.float64)
    return ds.summary(
        n_vertices=int(h["n_vertices"]),
        n_faces=int(ds.group["faces"].shape[0]),
        index_matched=h.get("request", {}).get("index_matched"),
        # light carried through the air from part to part: a tally's flag (false before it existed)
        reentry=h.get("request", {}).get("reentry", False) if h.get("source") != "photographs" else None,
        # the light that left unscattered: the mean fraction of a beam kept apart (R, G, B), or None where
        # R_d counts it (the tallies made before) or a photograph measured it
        unscattered=(
            np.asarray(ds.group["unscattered"][...], dtype=np.float64).mean(axis=0).round(6).tolist()
            if "unscattered" in ds.group
            else None
        ),
        incidence={**ds.incidence.describe(), "directions": ds.incidence.count},
        exit_bins=None if ds.exit_bins is None else ds.exit_bins.count,
        **object_bounds(vertices),
        **_photographs(h),
    )


def _photographs(h: dict) -> dict:
    """A data set measured from photographs: ``source``, its cameras (names and pose errors, px) and the
    exit law; its ``photons`` are the equivalent count of the measured noise."""
    if h.get("source") != "photographs":
        return {}
    p = h.get("photographs", {})
    return {
        "source": "photographs",
        "cameras": [
            {"name": c.get("name"), "reprojection_px": c.get("reprojection_px")} for c in p.get("cameras", [])
        ],
        "exit_law": (p.get("exit_law") or {}).get("law"),
    }
