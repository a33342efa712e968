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


def check_mesh(mesh, name: str = "mesh"):
    """Repair what can be repaired (with a warning) and refuse the rest; returns the mesh."""

    if len(mesh.faces) == 0:
        raise TranslucencyError(f"{name}: no triangles")
    if not np.isfinite(mesh.vertices).all():
        raise TranslucencyError(f"{name}: vertex coordinates are not finite")
    good = mesh.nondegenerate_faces()
    if not good.all():
        warnings.warn(f"{name}: removed {int((~good).sum())} degenerate (zero-area) triangles", stacklevel=2)
        mesh.update_faces(good)
        mesh.remove_unreferenced_vertices()
    mesh.merge_vertices()
    if not mesh.is_watertight:
        trimesh.repair.fill_holes(mesh)
        if mesh.is_watertight:
            warnings.warn(f"{name}: the surface was open; small holes were filled", stacklevel=2)
        else:
            open_edges = len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1))
            raise TranslucencyError(
                f"{name}: the surface is not closed ({open_edges} open or non-manifold edges); "
                "light transport inside an object needs a watertight mesh"
            )
    if not mesh.is_winding_consistent:
        trimesh.repair.fix_winding(mesh)
        warnings.warn(f"{name}: inconsistent triangle winding was fixed", stacklevel=2)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def load_mesh(path, *, scale_mm: float = 1.0):
    """Read a mesh file as a closed trimesh.Trimesh in mm.

    Parameters
    ----------
    path : path
        OBJ, PLY, STL, GLB, ... (anything trimesh reads as one mesh).
    scale_mm : float
        Millimetres per file unit (e.g. 1000 for a file in metres).

    Examples
    --------
    >>> import tempfile, trimesh
    >>> p = Path(tempfile.mkdtemp()) / "ball.ply"
    >>> _ = trimesh.creation.icosphere(3, radius=0.01).export(p)
    >>> round(float(load_mesh(p, scale_mm=1000).extents[0]), 3)
    20.0
    """

    path = Path(path)
    if not path.exists():
        raise TranslucencyError(f"{path}: no such mesh file")
    if not (np.isfinite(scale_mm) and scale_mm > 0):
        raise TranslucencyError(f"scale: must be a positive number of mm per file unit, got {scale_mm}")
    try:
        mesh = trimesh.load(path, force="mesh", process=True)
    except Exception as exc:  # noqa: BLE001 — any parser failure is the file's fault
        raise TranslucencyError(
            f"{path}: not a readable mesh ({type(exc).__name__}: {str(exc)[:80]})"
        ) from None
    if not isinstance(mesh, trimesh.Trimesh):
        raise TranslucencyError(f"{path}: holds no triangle mesh")
    mesh.apply_scale(scale_mm)
    return check_mesh(mesh, str(path))
