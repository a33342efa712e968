"""Reading a user's mesh (OBJ, PLY, STL, ... via trimesh), in millimetres, checked for transport.

Photon transport inside an object needs a closed, consistently oriented
surface.  :func:`load_mesh` reads the file, scales it to mm, drops degenerate
(zero-area) triangles and duplicate vertices with a warning, fills small holes
with a warning, and refuses — with one line naming the file — what it cannot
make closed.  Vertex normals are recomputed from the faces (files without
normals are fine).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import trimesh

from .._validate import TranslucencyError


def close_holes(mesh) -> list[float]:
    """Close every hole (boundary loop) by a fan of triangles around the loop's centroid, oriented like
    the surface around it; returns the loops' perimeters (mm).

    Raises ``TranslucencyError`` where the boundary does not form simple loops (non-manifold edges).
    """
    edges = np.asarray(mesh.edges)  # directed, in each face's order
    key = np.sort(edges, axis=1)
    _, inverse, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    boundary = edges[count[inverse.ravel()] == 1]
    if len(boundary) == 0:
        return []
    following = dict(zip(boundary[:, 0].tolist(), boundary[:, 1].tolist()))
    if len(following) != len(boundary) or (count > 2).any():
        raise TranslucencyError("mesh: its open edges do not form simple loops (non-manifold boundary)")
    vertices, faces, perimeters, seen = list(np.asarray(mesh.vertices)), [], [], set()
    v = np.asarray(mesh.vertices, dtype=np.float64)
    for start in following:
        if start in seen:
            continue
        loop, node = [start], following[start]
        seen.add(start)
        while node != start:
            if node in seen or node not in following:
                raise TranslucencyError(
                    "mesh: its open edges do not form simple loops (non-manifold boundary)"
                )
            loop.append(node)
            seen.add(node)
            node = following[node]
        ring = v[loop]
        perimeters.append(float(np.linalg.norm(ring - np.roll(ring, -1, axis=0), axis=1).sum()))
        centre = len(vertices)
        vertices.append(ring.mean(axis=0))
        # an open edge a→b belongs to a face that runs a→b; the patch runs b→a to match it
        faces += [[b, a, centre] for a, b in zip(loop, loop[1:] + loop[:1])]
    mesh.vertices = np.asarray(vertices)
    mesh.faces = np.concatenate([np.asarray(mesh.faces), np.asarray(faces, dtype=np.int64)])
    return perimeters


def check_mesh(mesh, name: str = "mesh", *, max_hole: float = 0.5):
    """Repair what can be repaired (with a warning) and refuse the rest; returns the mesh.

    Duplicate vertices are merged whatever their texture coordinates or normals (a UV seam splits a
    closed surface), degenerate triangles dropped, holes whose perimeter is at most ``max_hole`` times the
    mesh's bounding-box diagonal closed (:func:`close_holes`), the winding made consistent and outward.
    """
    if len(mesh.faces) == 0:
        raise TranslucencyError(f"{name}: no triangles")
    if not np.isfinite(mesh.vertices).all():
        raise TranslucencyError(f"{name}: vertex coordinates are not finite")
    good = mesh.nondegenerate_faces()
    if not good.all():
        warnings.warn(f"{name}: removed {int((~good).sum())} degenerate (zero-area) triangles", stacklevel=2)
        mesh.update_faces(good)
        mesh.remove_unreferenced_vertices()
    mesh.merge_vertices(merge_tex=True, merge_norm=True)  # seams of a texture or normal map are one surface
    if not mesh.is_watertight:
        diagonal = float(np.linalg.norm(mesh.extents))
        open_edges = len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1))
        shared = _edges_of_more_than_two(mesh)
        n_faces = len(mesh.faces)
        try:
            perimeters = close_holes(mesh)
        except TranslucencyError:
            perimeters = None
        if perimeters is not None and mesh.is_watertight and max(perimeters) <= max_hole * diagonal:
            warnings.warn(
                f"{name}: the surface was open; {len(perimeters)} holes were filled (largest perimeter "
                f"{max(perimeters):.3g} mm on a {diagonal:.3g} mm object)",
                stacklevel=2,
            )
        else:
            what = [f"{open_edges} open edges"] if open_edges else []
            what += [f"{shared} edges shared by more than two triangles"] if shared else []
            if perimeters:
                holes = f"{len(perimeters)} hole" + ("s" if len(perimeters) > 1 else "")
                what.append(f"{holes}, up to {max(perimeters):.3g} mm around")
            flat = " — a single triangle has no volume" if n_faces == 1 else ""
            raise TranslucencyError(
                f"{name}: the surface is not closed ({', '.join(what)}){flat}; light transport inside an "
                "object needs a watertight mesh"
            )
    if not mesh.is_winding_consistent:
        trimesh.repair.fix_winding(mesh)
        warnings.warn(f"{name}: inconsistent triangle winding was fixed", stacklevel=2)
    with np.errstate(invalid="ignore", divide="ignore"):  # a flat surface's centre of mass divides by 0
        volume = float(mesh.volume)
    if volume < 0:
        mesh.invert()
    if not abs(volume) > 1e-9 * float(np.linalg.norm(mesh.extents)) ** 3:
        raise TranslucencyError(
            f"{name}: the surface is closed but encloses no volume (flat or folded onto itself); light "
            "transport inside an object needs a solid"
        )
    return mesh


def _edges_of_more_than_two(mesh) -> int:
    """Edges that more than two triangles share (non-manifold: no inside and outside there)."""
    _, count = np.unique(np.asarray(mesh.edges_sorted), axis=0, return_counts=True)
    return int((count > 2).sum())


#: object sizes (bounding-box diagonal, mm) a scan is plausible for; outside, ``load_mesh`` warns about units
PLAUSIBLE_MM = (2.0, 5000.0)

#: rotations turning a file's up axis into our +z
_UP = {
    "z": np.eye(3),
    "y": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),  # +y → +z (x stays, z → −y)
    "x": np.array([[0, 0, -1.0], [0, 1, 0], [1, 0, 0]]),  # +x → +z
}


def check_mesh_file(path, option: str = "path") -> Path:
    """``path`` as a Path when it is a file; one line naming ``option`` when it is missing or a folder."""
    path = Path(path)
    if path.is_dir():
        raise TranslucencyError(
            f"{option} {path}: is a folder, not a mesh file; give the file itself (OBJ, PLY, STL, ...)"
        )
    if not path.exists():
        raise TranslucencyError(f"{option} {path}: no such mesh file")
    return path


def load_mesh(path, *, scale_mm: float = 1.0, up: str = "z"):
    """Read a mesh file as a closed trimesh.Trimesh in mm.

    Parameters
    ----------
    path : path
        OBJ, PLY, STL, GLB, ... (anything trimesh reads as one mesh).
    scale_mm : float
        Millimetres per file unit (e.g. 1000 for a file in metres).
    up : {"z", "y", "x"}
        The file's up axis, turned to +z (many OBJ files are y-up).

    Examples
    --------
    >>> import tempfile, trimesh
    >>> p = Path(tempfile.mkdtemp()) / "ball.ply"
    >>> _ = trimesh.creation.icosphere(3, radius=0.01).export(p)
    >>> round(float(load_mesh(p, scale_mm=1000).extents[0]), 3)
    20.0
    """

    path = check_mesh_file(path)
    if not (np.isfinite(scale_mm) and scale_mm > 0):
        raise TranslucencyError(f"scale_mm: must be a positive number of mm per file unit, got {scale_mm}")
    try:
        mesh = trimesh.load(path, force="mesh", process=True)
    except Exception as exc:  # noqa: BLE001 — any parser failure is the file's fault
        raise TranslucencyError(
            f"{path}: not a readable mesh ({type(exc).__name__}: {str(exc)[:80]})"
        ) from None
    if not isinstance(mesh, trimesh.Trimesh):
        raise TranslucencyError(f"{path}: holds no triangle mesh")
    mesh.apply_scale(scale_mm)
    size = float(np.linalg.norm(mesh.extents)) if len(mesh.vertices) else 0.0
    if len(mesh.vertices) and not PLAUSIBLE_MM[0] <= size <= PLAUSIBLE_MM[1]:
        hint = (
            f"scale_mm={1000 * scale_mm:g} if it is in metres"
            if size < PLAUSIBLE_MM[0]
            else "a smaller scale_mm"
        )
        warnings.warn(
            f"{path}: the object is {size:.3g} mm across at scale_mm={scale_mm:g} mm per unit; "
            f"translucent objects are {PLAUSIBLE_MM[0]:g}–{PLAUSIBLE_MM[1]:g} mm — {hint}?",
            stacklevel=2,
        )
    if up not in _UP:
        raise TranslucencyError(f"up: expected one of {', '.join(_UP)}, got {up!r}")
    if up != "z":
        rotation = np.eye(4)
        rotation[:3, :3] = _UP[up]
        mesh.apply_transform(rotation)
    return check_mesh(mesh, str(path))
