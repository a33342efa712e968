"""Speed and memory of the planar fit against scipy point by point (issue 4, item 5).

1. **Whole fit**: ``fit_planar`` (iso and aniso m = 8, with α) on a virtual-DISCO
   data set of 64 × 64 incident points with 65 × 65-pixel windows (made on first
   use, ~1 min), each in a fresh process so that its peak memory (max RSS minus
   the interpreter's) can be compared with the data set's size.
2. **Solver against scipy, same objective**: for a sample of incident points, the
   first round's objective (α = 1, the fitter's weights) is minimised
   (a) by our batched variable projection on the grouped radii and
   (b) by ``scipy.optimize.least_squares`` point by point and channel by channel
   over the window's pixels (c ≥ 0 and d < 0 by bounds, three starts as ours);
   both costs are evaluated pixel by pixel with the same weights.

    python benchmarks/fit_speed.py [--data bench_data/fit64.zarr] [--sample 48]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np


def make_data(path: Path) -> None:
    cmd = [
        sys.executable,
        "-m",
        "translucency",
        "acquire",
        "planar",
        "--material",
        "marble",
        "--size",
        "36",
        "36",
        "8",
        "--voxel",
        "0.25",
        "--grid",
        "64",
        "--span",
        "15.75",
        "--pitch",
        "0.25",
        "--window",
        "16",
        "--photons",
        "4000",
        "--seed",
        "7",
        "--dtype",
        "float16",
        "--chunk",
        "256",
        "--out",
        str(path),
    ]
    subprocess.run(cmd, check=True)


def _child(path, kind, queue):
    from translucency.fit.planar import fit_planar

    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t = time.perf_counter()
    fit = fit_planar(path, kind, n_directions=8)
    sec = time.perf_counter() - t
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    queue.put(
        {
            "kind": kind,
            "seconds": sec,
            "rounds": len(fit.history),
            "peak_mb": (peak - base) / 1024,
            "flagged": int(fit.flagged.sum()),
        }
    )


def whole_fit(path: Path, kind: str) -> dict:
    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    p = ctx.Process(target=_child, args=(str(path), kind, q))
    p.start()
    out = q.get()
    p.join()
    return out


def solver_vs_scipy(path: Path, n_sample: int) -> dict:
    from scipy.optimize import least_squares

    from translucency.fit._pixels import grouped as _grouped
    from translucency.fit.chunk import load_chunk as _load_chunk
    from translucency.fit.chunk import weights as _weights
    from translucency.fit.context import FitContext
    from translucency.fit.families import FAMILIES
    from translucency.fit.planar import _PlanarSource
    from translucency.fit.state import FitState
    from translucency.geometry import SampleGrid
    from translucency.io.dataset import open_dataset
    from translucency.solvers.varpro import fit_exponentials_batched

    ds = open_dataset(path)
    rng = np.random.default_rng(0)
    pts = np.sort(rng.choice(ds.n_points, n_sample, replace=False))
    x_i, origin = ds["x_i"].astype(float), ds["window_origin"].astype(float)
    grid = SampleGrid.covering(origin, ds.pitch, ds.window)
    photons = ds.header["acquisition"]["photons"]
    source = _PlanarSource(ds, grid, origin, 1 / (photons * ds.pitch**2))
    ctx = FitContext(
        source=source,
        family=FAMILIES["iso"],
        n=3,
        m=1,
        C=3,
        exclusion=ds.pitch,
        rel_sigma=0.05,
        eta=1.3,
        radius_step=ds.pitch / 4,
        sweeps=1,
        balance=True,
        x_i=x_i,
    )
    state = FitState(ds.n_points, 3, 1, 3, grid.shape)
    # the sampled points, through the fitter's own loading and weighting (first round, α = 1)
    chunks = [_load_chunk(ctx, state, p, p + 1) for p in pts]
    w2 = [_weights(ctx, ch, None) for ch in chunks]

    def pixel_cost(ch, w, c, a):  # Σ w² (f − y)² over the window, per channel
        f = np.einsum("jck,jck->jc", c[None], np.exp(-a[None] * ch.r[0][:, None, None]))
        return (w[0] * (f - ch.y[0]) ** 2).sum(0)

    # (a) ours: batched over all sampled points and channels
    t = time.perf_counter()
    ours = []
    for ch, w in zip(chunks, w2):
        W, Y = _grouped(ch.rings, ch.r_g.size, 3, w, np.float32(1.0), ch.y)
        ours.append((ch.r_g, W, Y))
    # one batched call over every sampled (point, channel), as in the fitter (same radii for all windows)
    r_g = ours[0][0]
    W = np.concatenate([o[1] for o in ours])
    Y = np.concatenate([o[2] for o in ours])
    c, a, _ = fit_exponentials_batched(r_g, W, Y, 3)
    t_ours = time.perf_counter() - t
    cost_ours = np.concatenate(
        [
            pixel_cost(ch, w, c[3 * i : 3 * i + 3], a[3 * i : 3 * i + 3])
            for i, (ch, w) in enumerate(zip(chunks, w2))
        ]
    )

    # (b) scipy point by point, channel by channel, on the pixels
    t = time.perf_counter()
    cost_scipy = []
    for ch, w in zip(chunks, w2):
        r = ch.r[0].astype(np.float64)
        for lam in range(3):
            y, sw = ch.y[0, :, lam].astype(np.float64), np.sqrt(w[0, :, lam].astype(np.float64))

            def res(p, sw=sw, r=r, y=y):
                return sw * (np.exp(-np.exp(p[3:])[None] * r[:, None]) @ p[:3] - y)

            best = None
            for start in range(3):
                a0 = np.exp(
                    np.log(0.1)
                    + (np.log(32) - np.log(0.1)) * (np.arange(3) + 0.5 + 0.5 * (start - 1) / 3) / 3
                )
                x0 = np.concatenate([np.full(3, max(y.max(), 1e-6) / 3), np.log(a0)])
                sol = least_squares(
                    res, x0, bounds=([0, 0, 0, -5, -5, -5], [np.inf] * 3 + [6, 6, 6]), method="trf"
                )
                if best is None or sol.cost < best.cost:
                    best = sol
            cost_scipy.append(2 * best.cost)
    t_scipy = time.perf_counter() - t
    cost_scipy = np.array(cost_scipy)
    return {
        "points": int(n_sample),
        "problems": int(3 * n_sample),
        "ours_s": t_ours,
        "scipy_s": t_scipy,
        "speedup": t_scipy / t_ours,
        "cost_ratio_median": float(np.median(cost_ours / cost_scipy)),
        "cost_ratio_max": float(np.max(cost_ours / cost_scipy)),
        "ours_not_worse_fraction": float(np.mean(cost_ours <= cost_scipy * (1 + 1e-3))),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", type=Path, default=Path("bench_data/fit64.zarr"))
    ap.add_argument("--sample", type=int, default=48, help="incident points for the scipy comparison")
    ap.add_argument("--kinds", default="iso,aniso", help="whole fits to time (comma-separated; empty: none)")
    args = ap.parse_args()
    if not args.data.exists():
        make_data(args.data)
    from translucency.io.dataset import open_dataset

    ds = open_dataset(args.data)
    P, (H, W) = ds.n_points, ds.window
    size_mb = P * H * W * (3 * 4 * 2 + 1) / 2**20  # R_d and variance as float32, mask
    print(f"data set: {P} incident points, {H}x{W}-pixel windows; in memory as float32 {size_mb:.0f} MiB")
    result = {"data": str(args.data), "points": P, "window": [H, W], "in_memory_mib": size_mb}
    for kind in filter(None, args.kinds.split(",")):
        r = whole_fit(args.data, kind)
        result[kind] = r
        print(
            f"fit {kind:5s}: {r['seconds']:6.1f} s  ({r['rounds']} rounds)  "
            f"peak memory {r['peak_mb']:.0f} MiB "
            f"= {r['peak_mb'] / size_mb:.2f} x the data set"
        )
    if args.sample <= 0:
        print(json.dumps(result, indent=1))
        return
    s = solver_vs_scipy(args.data, args.sample)
    result["solver_vs_scipy"] = s
    print(
        "solver vs scipy.optimize.least_squares per point "
        f"({s['problems']} profile problems, same objective):"
    )
    print(
        f"  ours {s['ours_s']:.2f} s, scipy {s['scipy_s']:.1f} s  -> {s['speedup']:.0f}x faster; "
        f"cost ours/scipy median {s['cost_ratio_median']:.4f} (max {s['cost_ratio_max']:.4f}), "
        f"ours not worse in {100 * s['ours_not_worse_fraction']:.0f} %"
    )
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
