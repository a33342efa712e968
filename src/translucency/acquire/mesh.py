r"""Virtual DISCO on a 3D object: pencil beams at surface points, exits tallied per vertex.

For each incident vertex :math:`x_i` (a farthest-point sample of the mesh's
vertices) N photons per channel enter along the inward normal
(:mod:`translucency.acquire.mesh_walk`); each photon leaving the surface is
given to its nearest vertex v, and

.. math:: R_d(x_i, v) = \frac{n_v}{N A_v}\quad[\mathrm{mm}^{-2}],

with :math:`A_v` the vertex's area (a third of its triangles').  Light
reflected by Fresnel at the entry is recorded apart (``specular``).

Mesh data set (Zarr v3 directory, header key ``translucency_mesh_dataset``,
version 1): ``vertices`` (V, 3) mm, ``faces`` (F, 3), ``vertex_area`` (V,)
mm², ``normals`` (V, 3), ``incident`` (P,) vertex indices, ``R_d`` (P, V, 3)
per unit incident power, ``specular`` (P, 3), ``chunk_done`` (resume marker,
written last per chunk of points).  Same arguments resume; other arguments
are refused unless ``overwrite``.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .._validate import TranslucencyError
from .._version import __version__
from ..io.outputs import claim_output, remove_dataset
from .mesh_walk import EXIT, mesh_random_walk, mesh_scene
from .volume import Volume

HEADER_KEY = "translucency_mesh_dataset"
FORMAT = "translucency-mesh-dataset"
VERSION = 1


def farthest_points(vertices: np.ndarray, k: int, start: int = 0) -> np.ndarray:
    """Indices of k vertices spread over the surface by farthest-point sampling (Euclidean).

    Examples
    --------
    >>> v = np.array([[0.0, 0, 0], [1, 0, 0], [10, 0, 0], [5, 0, 0]])
    >>> farthest_points(v, 3).tolist()
    [0, 2, 3]
    """
    k = int(k)
    if not 1 <= k <= len(vertices):
        raise TranslucencyError(f"points: need 1 to {len(vertices)} incident points, got {k}")
    chosen = [int(start)]
    d = np.linalg.norm(vertices - vertices[start], axis=1)
    for _ in range(k - 1):
        nxt = int(np.argmax(d))
        chosen.append(nxt)
        d = np.minimum(d, np.linalg.norm(vertices - vertices[nxt], axis=1))
    return np.array(chosen)


def vertex_areas(mesh) -> np.ndarray:
    """A third of the area of the triangles around each vertex, mm²."""
    return np.bincount(mesh.faces.ravel(), np.repeat(mesh.area_faces / 3.0, 3), minlength=len(mesh.vertices))


def acquire_mesh(mesh, volume: Volume, out, *, n_points: int = 64, photons: int = 20_000, seed: int = 0,
                 chunk_points: int = 8, index_matched: bool = False, overwrite: bool = False, inputs=(),
                 progress: Callable[[int, int], None] | None = None):
    """Scan pencil beams over a closed mesh filled with ``volume``; write a mesh data set.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Closed surface in mm (see :func:`translucency.io.mesh.load_mesh`).
    volume : Volume
        Coefficients over the mesh's bounding box (object space; z index 0 at the top).
    out : path
        Zarr directory.
    n_points, photons, seed, chunk_points
        Incident vertices, photons per point and channel, seed, points per chunk.

    Returns
    -------
    pathlib.Path
    """
    import zarr
    from scipy.spatial import cKDTree
    from zarr.codecs import BloscCodec


    if photons < 1:
        raise TranslucencyError(f"photons: must be >= 1, got {photons}")
    need = np.asarray(mesh.extents) - np.asarray(volume.size_mm)
    if (need > 1e-6).any():
        raise TranslucencyError(f"volume: {volume.size_mm} mm does not cover the mesh's bounding box "
                                f"{tuple(np.round(mesh.extents, 2))} mm")
    V = len(mesh.vertices)
    incident = farthest_points(np.asarray(mesh.vertices), n_points)
    P = len(incident)
    request = {"n_points": P, "photons": int(photons), "seed": int(seed), "chunk": int(chunk_points),
               "index_matched": bool(index_matched), "vertices": V, "faces": len(mesh.faces),
               "volume": volume.description, "bounds": np.round(mesh.bounds, 6).tolist(),
               "volume_grid": {"voxel_mm": volume.voxel_mm, "size_mm": list(volume.size_mm)}}
    request = json.loads(json.dumps(request))
    out = Path(out)
    root = None
    if claim_output(out, "mesh data set", overwrite=overwrite, inputs=inputs, reuse=True):
        try:
            old = zarr.open_group(str(out), mode="r+")
            same = dict(old.attrs).get(HEADER_KEY, {}).get("request") == request
        except Exception:  # noqa: BLE001
            same = False
        if same and not overwrite:
            root = old
        elif not overwrite:
            raise TranslucencyError(f"--out {out}: a mesh data set made with other arguments is already there; "
                                    "choose another path or pass --overwrite to replace it")
        else:
            remove_dataset(out)
    n_chunks = -(-P // chunk_points)
    area = vertex_areas(mesh)
    if root is None:
        header = {"format": FORMAT, "version": VERSION, "units": {"length": "mm", "R_d": "mm^-2"},
                  "n_points": P, "n_vertices": V, "photons": int(photons), "seed": int(seed),
                  "eta": volume.eta, "g": volume.g, "sample": volume.description,
                  "software": {"translucency": __version__}, "request": request}
        root = zarr.create_group(str(out), attributes={HEADER_KEY: header}, overwrite=False)  # never clears a folder
        comp = BloscCodec(cname="zstd", clevel=5, shuffle="shuffle")
        for name, data in (("vertices", mesh.vertices.astype(np.float32)), ("faces", mesh.faces.astype(np.int32)),
                           ("normals", mesh.vertex_normals.astype(np.float32)),
                           ("vertex_area", area.astype(np.float32)), ("incident", incident.astype(np.int32))):
            root.create_array(name, data=data, compressors=comp)
        root.create_array("R_d", shape=(P, V, 3), dtype="float32", chunks=(chunk_points, V, 3),
                          compressors=comp, fill_value=0)
        root.create_array("specular", shape=(P, 3), dtype="float32", chunks=(chunk_points, 3), fill_value=0)
        root.create_array("chunk_done", shape=(n_chunks,), dtype="bool", chunks=(1,), fill_value=False)
    scene = mesh_scene(mesh)
    tree = cKDTree(mesh.vertices)
    done = np.asarray(root["chunk_done"][...])
    normals = np.asarray(mesh.vertex_normals)
    for c in range(n_chunks):
        lo, hi = c * chunk_points, min(P, (c + 1) * chunk_points)
        if done[c]:
            continue
        R = np.zeros((hi - lo, V, 3), np.float32)
        spec = np.zeros((hi - lo, 3), np.float32)
        for ch in range(3):
            res = mesh_random_walk(scene, mesh.bounds, volume, ch, mesh.vertices[incident[lo:hi]],
                                   normals[incident[lo:hi]], photons, seed=seed + 7919 * ch, first_point=lo,
                                   index_matched=index_matched)
            point = np.repeat(np.arange(hi - lo), photons)
            ok = res.code == EXIT
            _, v = tree.query(res.position[ok])
            counts = np.bincount(point[ok] * V + v, minlength=(hi - lo) * V).reshape(hi - lo, V)
            R[..., ch] = counts / (photons * area)
            spec[:, ch] = np.bincount(point[res.code == -1], minlength=hi - lo) / photons
        root["R_d"][lo:hi] = R
        root["specular"][lo:hi] = spec
        root["chunk_done"][c] = True  # last: the chunk is complete
        if progress:
            progress(hi, P)
    return out


def object_volume(name: str, mesh, voxel_mm: float, *, g: float = 0.0, seed: int = 0) -> Volume:
    """A generated sample (``make_sample`` names) sized to the mesh's bounding box."""
    from .samples import make_sample

    size = tuple(float(np.ceil(e / voxel_mm) * voxel_mm) for e in mesh.extents)
    return make_sample(name, size, voxel_mm, g=g, seed=seed)
