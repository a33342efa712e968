"""Import throughput of HDR photographs (issue 15, item 4): MB/s of image files turned into a data set.

A folder of ``--images`` synthetic photographs (``--size`` W H pixels, RGB float32 PFM or OpenEXR) of an
exponential spot seen through an oblique homography, with a dark frame, a flat field and vignetting, is
imported with ``translucency.rig.import_images`` (hashing every file for provenance, reading, correcting
the part under each window, resampling 8 × 8 mm windows at 0.25 mm).  Throughput = bytes of image files /
wall time of the import (the files are read once beforehand, so that the page cache holds them as it
would on a second pass of a lab's disk); also per CPU second of the process, which a busy shared machine
disturbs less, and the load average at the end.

    python benchmarks/import_speed.py [--images 48] [--size 1024 1024] [--format pfm|exr]

Target: ≥ 100 MB/s on 2 cores (PFM).
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from translucency.rig import Calibration, ImportSetup, import_images, write_pfm
from translucency.rig.planar.photographs import VirtualCamera
from translucency.rig.shared.hdr import write_exr


def make_folder(folder: Path, n: int, size: tuple[int, int], fmt: str) -> tuple[Calibration, int]:
    W, H = size
    cam = VirtualCamera((10.0, -8.0, 22.0), (10.0, 10.0, 0.0), 40.0, W, H)
    hom = cam.homography()
    v, u = np.mgrid[0:H, 0:W].astype(np.float32)
    xy = hom.to_sample(np.stack([u.ravel(), v.ravel()], 1)).reshape(H, W, 2).astype(np.float32)
    rng = np.random.default_rng(0)
    dark = np.full((H, W, 3), 0.01, np.float32)
    flat = (1 + 0.01 * rng.standard_normal((H, W, 3))).astype(np.float32)
    rows = ["file,x,y,power"]
    pts = 10 + rng.uniform(-3, 3, (n, 2))
    for j, p in enumerate(pts):
        r = np.hypot(xy[..., 0] - p[0], xy[..., 1] - p[1])
        img = (np.exp(-1.5 * r)[..., None] * [1.0, 0.8, 0.6] + dark).astype(np.float32)
        name = f"shot_{j:03d}.{fmt}"
        (write_pfm if fmt == "pfm" else write_exr)(folder / name, img)
        rows.append(f"{name},{p[0]:.4f},{p[1]:.4f},1.0")
    (folder.parent / "positions.csv").write_text("\n".join(rows) + "\n")
    calib = Calibration(hom, scale=1.0, dark=dark, flat=flat, vignetting=(-0.2,), gain=0.01, read_noise=0.01)
    return calib, sum(f.stat().st_size for f in folder.iterdir())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--images", type=int, default=48)
    ap.add_argument("--size", type=int, nargs=2, default=(1024, 1024))
    ap.add_argument("--format", choices=("pfm", "exr"), default="pfm")
    ap.add_argument("--repeat", type=int, default=2, help="imports timed (the best is quoted)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "images"
        folder.mkdir()
        calib, nbytes = make_folder(folder, args.images, tuple(args.size), args.format)
        for f in folder.iterdir():  # warm the page cache
            f.read_bytes()
        times, cpu = [], []
        for k in range(args.repeat):
            t0, c0 = time.perf_counter(), time.process_time()
            import_images(
                folder,
                Path(tmp) / "positions.csv",
                calib,
                Path(tmp) / f"out{k}.zarr",
                ImportSetup(window=8.0),
            )
            times.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
        best = min(times)
        print(
            json.dumps(
                {
                    "images": args.images,
                    "size": list(args.size),
                    "format": args.format,
                    "MB": round(nbytes / 1e6, 1),
                    "seconds": [round(t, 3) for t in times],
                    "MB_per_s": round(nbytes / 1e6 / best, 1),
                    "cpu_seconds": [round(t, 3) for t in cpu],
                    "MB_per_cpu_s": round(nbytes / 1e6 / min(cpu), 1),
                    "load_average": [round(v, 2) for v in os.getloadavg()],
                    "images_per_s": round(args.images / best, 2),
                }
            )
        )


if __name__ == "__main__":
    main()
