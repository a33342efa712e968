"""The cost of the angle axes in ``acquire mesh`` and ``acquire planar`` (issue 37, item 2): time per photon
and size on disk.

Times, in one run, the same acquisition three ways — the paper's normal beams (the baseline), the same
with exit bins, and normal + oblique beams (``--incidence 60 --azimuths 4``) with exit bins — and prints
seconds per photon walked (photons × directions × 3 channels) with its ratio to the baseline, and each
data set's size on disk (Zarr, Zstandard)::

    python benchmarks/acquire_angles_cost.py [MESH.obj] [--size=20] [--points=8] [--photons=20000]
        [--material=marble] [--repeats=2] [--planar=1]

MESH defaults to ``../shared/meshes/spot.obj`` when it is there, else a 2,562-vertex icosphere.  The first
run of each way is a warm-up (Dr.Jit compiles its kernels); the medians of ``--repeats`` further runs are
printed.  ``--planar=1``: the same three ways on a planar scan instead (a 30 × 30 × 10 mm slab of the
material at 0.5 mm voxels, ``--points`` incident points in a row, windows of 10 mm at 0.25 mm pixels).
"""

from __future__ import annotations

import shutil
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from _options import options, sized_mesh
from translucency.acquire.mesh import acquire_mesh, object_volume
from translucency.angles import ExitBins, Incidence

DEFAULTS = {"size": 20.0, "points": 8, "photons": 20000, "material": "marble", "repeats": 2, "planar": 0}


def _bytes(path: Path) -> int:
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())


def main(argv) -> None:
    path, o = options(argv, DEFAULTS)
    if o["planar"]:
        from translucency.acquire import make_sample
        from translucency.acquire.planar import PlanarSetup, acquire_planar

        volume = make_sample(o["material"], (30.0, 30.0, 10.0), 0.5, seed=1)
        setup = PlanarSetup(
            grid=(o["points"], 1), span=(10.0, 1.0), pitch=0.25, window=10.0, photons=o["photons"],
            index_matched=True,
        )  # fmt: skip
        what = f"a {o['material']} slab 30 x 30 x 10 mm, windows of {setup.window_pixels()}^2 pixels"

        def acquire(out, **kw):
            acquire_planar(volume, replace(setup, **kw), out)
    else:
        mesh = sized_mesh(path, o["size"])
        volume = object_volume(o["material"], mesh, 0.5, seed=1)
        what = f"{len(mesh.vertices):,} vertices"

        def acquire(out, **kw):
            n, photons = o["points"], o["photons"]
            acquire_mesh(mesh, volume, out, n_points=n, photons=photons, index_matched=True, **kw)

    ways = {
        "normal beams (baseline)": dict(),
        "normal + exit bins (3 x 2)": dict(exit_bins=ExitBins(3)),
        "normal + 60 deg x 4 azimuths + exit bins": dict(
            incidence=Incidence((60.0,), 4), exit_bins=ExitBins(3)
        ),
    }
    folder = Path(tempfile.mkdtemp(prefix="angles-cost-"))
    print(
        f"{what}, {o['points']} points x {o['photons']:,} photons x 3 channels, "
        f"{o['material']}, {o['repeats']} timed runs after a warm-up"
    )
    base = None
    for name, kw in ways.items():
        directions = kw.get("incidence", Incidence()).count
        seconds = []
        for r in range(1 + o["repeats"]):
            out = folder / f"{len(seconds)}.zarr"
            shutil.rmtree(out, ignore_errors=True)
            t = time.perf_counter()
            acquire(out, **kw)
            if r:
                seconds.append(time.perf_counter() - t)
        walked = o["points"] * o["photons"] * 3 * directions
        per = float(np.median(seconds)) / walked
        base = base or per
        print(
            f"{name:44s} {np.median(seconds):7.2f} s  {per * 1e6:6.2f} us/photon  "
            f"x{per / base:4.2f} per photon  {_bytes(out) / 2**20:7.2f} MiB on disk"
        )
    shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main(sys.argv)
