"""A light's relight with the paper's shared colour (one sparse matrix, the colour scale riding with E)
against a fall-off per channel (three matrices on the same pairs), the main job's pig, side by side:

    python benchmarks/colour_relight.py [--data results/pig.zarr]

(``make demo`` leaves the pig's data set at ``results/pig.zarr``.)  Prints each time and their ratio.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from translucency.fit.mesh import fit_mesh
from translucency.mitsuba import mesh_scene
from translucency.pipeline import figure2_scene
from translucency.transport.irradiance import vertex_irradiance
from translucency.transport.matrices import transport_matrices
from translucency.transport.relight import relight_vertices


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", type=Path, default=Path("results/pig.zarr"))
    ap.add_argument("--repeats", type=int, default=10)
    args = ap.parse_args()
    mesh, _, light, _ = figure2_scene()
    E = vertex_irradiance(mesh, mesh_scene(mesh), light)
    seconds = {}
    for colour in ("shared", "per-channel"):
        T = transport_matrices(fit_mesh(args.data, "iso", colour=colour).model, mesh, through=False)
        relight_vertices(T, E)  # (compiled, warm)
        t = time.perf_counter()
        for _ in range(args.repeats):
            relight_vertices(T, E)
        seconds[colour] = (time.perf_counter() - t) / args.repeats
        print(
            f"{colour:<12} {seconds[colour] * 1e3:6.1f} ms a light "
            f"({len(T.matrices)} matrices, {T.nnz:,} pairs)"
        )
    print(f"per-channel / shared: {seconds['per-channel'] / seconds['shared']:.2f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
