"""Two closed meshes that no page of the docs uses, for trying a transport on shapes it was not tuned on.

- ``eared.obj``: a head (an ellipsoid, 24 × 20 × 22 mm) with two thin ears (flattened ellipsoids
  1.6 mm thick, 18 mm tall), joined by a smooth union of their signed distances.
- ``ring.obj``: a torus, 12 mm from its axis to the tube's centre, tube radius 4 mm.

Both are in mm (scale 1, +z up).  The head is the zero level set of its signed distance, meshed by marching
cubes (scikit-image) on a 0.6 mm grid and made watertight by trimesh:

    python benchmarks/own_meshes.py --out OUT_DIR

then pass ``--meshes OUT_DIR`` and a case spec naming ``eared.obj:1:z`` or ``ring.obj:1:z`` to
``default_transport.py``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import trimesh
from skimage.measure import marching_cubes


def _ellipsoid(p, centre, radii):
    """An ellipsoid's approximate signed distance (mm): (|q| − 1) · min radius, q the scaled offset."""
    q = (p - np.asarray(centre)) / np.asarray(radii)
    return (np.linalg.norm(q, axis=-1) - 1.0) * min(radii)


def _smooth_union(a, b, k=2.0):
    """The polynomial smooth minimum of two signed distances, blending over ``k`` mm."""
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b + (a - b) * h - k * h * (1.0 - h)


def eared(step: float = 0.6) -> trimesh.Trimesh:
    """The head with two thin ears (mm, +z up, ears in the x–z plane: thin along y)."""
    ax = np.arange(-16.0, 16.0 + step, step)
    az = np.arange(-14.0, 34.0 + step, step)
    X, Y, Z = np.meshgrid(ax, ax, az, indexing="ij")
    p = np.stack([X, Y, Z], axis=-1)
    d = _ellipsoid(p, (0, 0, 0), (12.0, 10.0, 11.0))
    for side in (-1.0, 1.0):  # each ear: thin along y, leaning outwards
        d = _smooth_union(d, _ellipsoid(p, (side * 7.5, 0.0, 18.0), (3.2, 0.8, 9.0)))
    verts, faces, _, _ = marching_cubes(d, level=0.0, spacing=(step, step, step))
    verts += np.array([ax[0], ax[0], az[0]])
    mesh = trimesh.Trimesh(verts, faces, process=True)
    trimesh.repair.fix_normals(mesh)
    return mesh


def ring() -> trimesh.Trimesh:
    """A torus in the x–y plane (mm)."""
    return trimesh.creation.torus(major_radius=12.0, minor_radius=4.0, major_sections=96, minor_sections=32)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    for name, mesh in (("eared", eared()), ("ring", ring())):
        assert mesh.is_watertight, name
        mesh.export(args.out / f"{name}.obj")
        print(f"{name}.obj: {len(mesh.vertices)} vertices, extents {np.round(mesh.extents, 1).tolist()} mm")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
