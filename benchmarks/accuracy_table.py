"""Accuracy table of the planar fits on virtual-DISCO data (issue 4, item 4).

For each sample (marble, apple-slice, skin, fibers, homogeneous marble) a
virtual acquisition is made (cached under --cache), then the isotropic
(per-channel and the paper's shared colour), anisotropic (m = 8), dipole and
Burley models are fitted with α and evaluated: relative L2 error overall and
per distance band, and the noise floor of the data.  Prints a Markdown table
and writes it with a JSON file.

    python benchmarks/accuracy_table.py --out docs/accuracy.md
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from translucency.acquire import PlanarSetup, acquire_planar, make_sample
from translucency.evaluate.errors import planar_errors
from translucency.fit.planar import fit_planar

SAMPLES = ["marble", "apple-slice", "skin", "fibers", "homogeneous:marble"]
FITS = {  # label -> fit_planar arguments
    "iso": dict(model="iso"),
    "iso shared colour": dict(model="iso", colour="shared"),
    "aniso m=8": dict(model="aniso", n_directions=8),
    "dipole": dict(model="dipole"),
    "burley": dict(model="burley"),
}


def acquire(sample: str, cache: Path, photons: int, grid: int) -> Path:
    path = cache / f"{sample.replace(':', '_')}_{grid}x{grid}_{photons}.zarr"
    vol = make_sample(sample, (20.0, 20.0, 8.0), 0.25, g=0.0, seed=1)
    setup = PlanarSetup(
        grid=(grid, grid),
        span=(6.0, 6.0),
        pitch=0.25,
        window=8.0,
        photons=photons,
        seed=1,
        chunk_points=grid * grid,
    )
    acquire_planar(vol, setup, path)  # resumes / reuses a finished data set made with the same arguments
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--photons", type=int, default=200_000)
    ap.add_argument("--grid", type=int, default=6)
    ap.add_argument("--cache", type=Path, default=Path("bench_data"))
    ap.add_argument("--samples", default=",".join(SAMPLES))
    ap.add_argument(
        "--out", type=Path, default=None, help="Markdown file for the table (and .json beside it)."
    )
    args = ap.parse_args()
    args.cache.mkdir(parents=True, exist_ok=True)
    results = {}
    for sample in args.samples.split(","):
        t = time.perf_counter()
        ds = acquire(sample, args.cache, args.photons, args.grid)
        print(f"{sample}: data {time.perf_counter() - t:.0f} s", flush=True)
        results[sample] = {}
        for label, kw in FITS.items():
            t = time.perf_counter()
            fit = fit_planar(ds, **kw)
            e = planar_errors(fit.model, ds, flagged=fit.flagged)
            results[sample][label] = {**e.summary(), "seconds": time.perf_counter() - t}
            print(
                f"  {label:18s} rel_l2 {100 * e.rel_l2:6.2f} %  near {100 * e.bands['near']:6.2f} %  "
                f"mid {100 * e.bands['mid']:6.2f} %  far {100 * e.bands['far']:6.2f} %",
                flush=True,
            )
    lines = [
        f"Virtual DISCO data: {args.grid}×{args.grid} incident points over 6 mm, 8 mm windows of 0.25 mm "
        f"pixels, {args.photons:,} photons per point and channel; slab 20×20×8 mm, 0.25 mm voxels, g = 0, "
        "η = 1.3. Relative L2 error (%) over all pairs / near (< 1 mm) / mid (1–4 mm) / far (> 4 mm); "
        "'noise' is the error the measurement noise alone would give.",
        "",
        "| sample | model | all | near | mid | far |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for sample, fits in results.items():
        for label, s in fits.items():
            lines.append(
                f"| {sample} | {label} | {100 * s['rel_l2']:.2f} | {100 * s['rel_l2_near']:.2f} | "
                f"{100 * s['rel_l2_mid']:.2f} | {100 * s['rel_l2_far']:.2f} |"
            )
        nf = next(iter(fits.values()))["noise_floor"]
        lines.append(
            f"| {sample} | *noise* | {100 * nf['all']:.2f} | {100 * nf['near']:.2f} | "
            f"{100 * nf['mid']:.2f} | {100 * nf['far']:.2f} |"
        )
    table = "\n".join(lines)
    print(table)
    if args.out:
        args.out.write_text(table + "\n")
        args.out.with_suffix(".json").write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
