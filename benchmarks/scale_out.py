"""Scale-out of fits and acquisitions on a Dask cluster (issue 16): 1 against 2 workers on this machine.

Measures, and writes to ``bench_data/scale_out.json``:

1. **Fit throughput** of ``fit_planar`` (iso, ``--rounds`` rounds, ``cache_mb=0``: every round reads its
   chunks again from the store — the out-of-core case) on a data set made by tiling the embedded marble
   data set ``--copies`` times side by side, with ``local:1`` and ``local:2`` (clusters started
   beforehand, workers warmed up), and in this process (threads) for reference; the ratio 2 / 1 worker;
   the decoded data rate per worker (R_d, variance and mask of every chunk read, per round).
2. **Memory per worker**: the peak resident set of each worker during the fit over its resident set
   before it (sampled every 10 ms in the worker), against one chunk's decoded data and the data set;
   the same for the driver (this process), and the bytes of α's statistics the driver holds: one
   running sum per statistic (one sample grid each) against the grid per chunk kept before issue 16's
   follow-up.
3. **Scheduler overhead**: empty tasks through the same path the fit's tasks take (per task), times the
   fit's task count, as a share of the fit's time; and the fit on ``local:1`` against threads with one
   thread (everything the cluster adds: transfers, α sent per round, results sent back).
4. **Acquisition throughput**: a small planar acquisition with ``local:1`` and ``local:2``.

Every result is also checked bit-identical to the threads run.  The machine may be shared: the load
average before and after is recorded.

    python benchmarks/scale_out.py [--copies 16] [--rounds 2] [--memory-limit 1GiB] [--skip-acquire]

(``--skip-acquire`` writes ``bench_data/scale_out_fit_COPIES.json``.)
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import threading
import time
from pathlib import Path

import numpy as np
from distributed import get_task_stream

from translucency.acquire import PlanarSetup, acquire_planar, make_sample
from translucency.cluster import open_cluster
from translucency.data import default_dataset_path
from translucency.fit import fit_planar
from translucency.fit.planar import default_chunk_points
from translucency.io.dataset import create_dataset, open_dataset, write_dataset

OUT = Path("bench_data")


def make_tiled(path: Path, copies: int):
    """The embedded data set ``copies`` times side by side (x shifted by the sample width), chunk by chunk."""
    src = open_dataset(default_dataset_path())
    if path.exists():
        ds = open_dataset(path)
        if ds.n_points == copies * src.n_points:
            return ds
    header = json.loads(json.dumps(src.header))
    P0 = src.n_points
    header["n_points"] = copies * P0
    header["request"] = {"written_by": "benchmarks/scale_out.py", "copies": copies}
    width = float(header["sample"]["size_mm"][0])
    header["sample"]["size_mm"][0] = width * copies
    ds = create_dataset(path, header, overwrite=True, resume=False)
    g, s = ds.group, src.group
    shift = np.array([width, 0.0], np.float32)
    g["x_i"][...] = np.concatenate([s["x_i"][...] + j * shift for j in range(copies)])
    g["window_origin"][...] = np.concatenate([s["window_origin"][...] + j * shift for j in range(copies)])
    k = int(header["chunk_points"])
    for j in range(copies):
        for lo in range(0, P0, k):
            hi = min(P0, lo + k)
            for name in ("R_d", "variance", "mask", "specular", "total_diffuse"):
                g[name][j * P0 + lo : j * P0 + hi] = s[name][lo:hi]
    g["chunk_done"][...] = True
    return open_dataset(path)


def _warm_worker(path: str) -> None:
    """In a worker process: a small fit of ``path`` in that process (imports, Numba's kernels)."""
    fit_planar(path, "iso", max_rounds=1, workers=1)


def _noop(i):
    return i


def _start_sampler(dask_worker=None):
    """In a worker: sample its resident set every 10 ms; return the current one."""
    import psutil

    proc = psutil.Process()
    state = {"peak": proc.memory_info().rss, "run": True}

    def loop():
        while state["run"]:
            state["peak"] = max(state["peak"], proc.memory_info().rss)
            time.sleep(0.01)

    dask_worker._translucency_sampler = state
    threading.Thread(target=loop, daemon=True).start()
    return state["peak"]


def _stop_sampler(dask_worker=None):
    state = dask_worker._translucency_sampler
    state["run"] = False
    return state["peak"]


class _Sampler:
    """This process's resident set, sampled every 10 ms in a thread while the block runs."""

    def __enter__(self):
        import psutil

        self._proc = psutil.Process()
        self.base = self.peak = self._proc.memory_info().rss
        self._run = True
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()
        return self

    def _loop(self):
        while self._run:
            self.peak = max(self.peak, self._proc.memory_info().rss)
            time.sleep(0.01)

    def __exit__(self, *exc):
        self._run = False
        self._thread.join()


def _same(a, b) -> bool:
    return bool(
        np.array_equal(a.model.c, b.model.c)
        and np.array_equal(a.model.d, b.model.d)
        and np.array_equal(a.model.alpha.values, b.model.alpha.values)
        and a.history == b.history
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--copies", type=int, default=16)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--memory-limit", default="1GiB")
    ap.add_argument("--skip-acquire", action="store_true")
    ap.add_argument("--skip-fit", action="store_true")
    args = ap.parse_args()
    OUT.mkdir(exist_ok=True)
    report: dict = {"load_before": os.getloadavg(), "cpus": os.cpu_count()}
    t = time.perf_counter()
    ds = make_tiled(OUT / f"scale_out_{args.copies}.zarr", args.copies)
    report["make_data_s"] = time.perf_counter() - t
    H, W = ds.window
    stored = int(ds.group["R_d"].chunks[0])
    chunk = default_chunk_points(ds.n_points, stored)  # fit_planar's default
    per_point = H * W * (3 * 4 + 3 * 4 + 1)  # decoded R_d, variance (float32) and mask
    n_tasks = -(-ds.n_points // chunk)
    report.update(
        points=ds.n_points,
        window=[H, W],
        fit_chunk_points=chunk,
        chunk_bytes=chunk * per_point,
        dataset_bytes=ds.n_points * per_point,
        tasks_per_round=n_tasks,
    )
    options = {"max_rounds": args.rounds, "cache_mb": 0}
    warm = write_dataset(  # a small data set for warming the workers up (imports, Numba's cache)
        OUT / "scale_out_warm.zarr",
        ds.read("x_i", 0, 32),
        ds.read("window_origin", 0, 32),
        ds.read("R_d", 0, 32),
        ds.pitch,
        variance=ds.read("variance", 0, 32),
        overwrite=True,
    )

    if not args.skip_fit:
        t = time.perf_counter()
        ref = fit_planar(ds, "iso", workers=1, **options)
        report["fit_threads_1_s"] = time.perf_counter() - t
        t = time.perf_counter()
        fit_planar(ds, "iso", **options)
        report["fit_threads_all_s"] = time.perf_counter() - t

        for n in (1, 2):
            with open_cluster(f"local:{n}", memory_limit=args.memory_limit) as cluster:
                client = cluster.client
                fit_planar(warm, "iso", max_rounds=1, scheduler=cluster)
                # and every worker on its own (the fit above may have run on one worker only): imports
                # and Numba's compiled kernels are loaded before the memory is sampled
                client.run(_warm_worker, str(warm.path))
                # scheduler overhead: empty tasks along the fit's path (one shared value, results back)
                shared = cluster.keep(0)
                t = time.perf_counter()
                for _ in cluster.run(_noop, [(i,) for i in range(400)], shared=()):
                    pass
                report[f"noop_task_ms_{n}w"] = (time.perf_counter() - t) / 400 * 1e3
                del shared
                base = client.run(_start_sampler)
                t = time.perf_counter()
                with get_task_stream(client=client) as stream, _Sampler() as driver:
                    fit = fit_planar(ds, "iso", scheduler=cluster, **options)
                secs = time.perf_counter() - t
                report[f"driver_peak_growth_MB_{n}w"] = (driver.peak - driver.base) / 1e6
                grid = fit.model.alpha.values.size
                report["alpha_grid_samples"] = grid
                report["alpha_sums_driver_MB"] = 2 * grid * 8 / 1e6  # Σw²Py, Σw²P²: float64, one grid each
                report["alpha_sums_per_chunk_grid_MB"] = n_tasks * 2 * grid * 8 / 1e6  # as kept before
                compute = sum(
                    ss["stop"] - ss["start"]
                    for task in stream.data
                    if str(task["key"]).startswith("_fit_task")
                    for ss in task["startstops"]
                    if ss["action"] == "compute"
                )
                report[f"fit_task_compute_s_{n}w"] = compute
                # the workers' time not spent on the fit's chunks: scheduler, transfers, the driver's α
                report[f"fit_not_computing_share_{n}w"] = 1 - compute / n / secs
                peak = client.run(_stop_sampler)
                report[f"fit_local{n}_s"] = secs
                report[f"fit_local{n}_identical"] = _same(fit, ref)
                report[f"worker_rss_before_MB_{n}w"] = [v / 1e6 for v in base.values()]
                report[f"worker_peak_growth_MB_{n}w"] = [(peak[w] - base[w]) / 1e6 for w in base]
                report[f"data_rate_MB_s_per_worker_{n}w"] = (
                    args.rounds * ds.n_points * per_point / secs / n / 1e6
                )

        report["fit_speedup_2w_over_1w"] = report["fit_local1_s"] / report["fit_local2_s"]
        tasks = args.rounds * n_tasks
        report["scheduler_overhead_share_noop"] = (
            tasks * report["noop_task_ms_1w"] / 1e3 / report["fit_local1_s"]
        )
        report["scheduler_overhead_share_vs_threads1"] = (
            report["fit_local1_s"] / report["fit_threads_1_s"] - 1
        )
        grow = max(report["worker_peak_growth_MB_1w"] + report["worker_peak_growth_MB_2w"]) * 1e6
        report["worker_peak_growth_over_chunk"] = grow / report["chunk_bytes"]

    if not args.skip_acquire:
        vol = make_sample("marble", (24, 24, 6), 0.25, seed=1)
        setup = PlanarSetup(
            grid=(16, 16), span=(12.0, 12.0), pitch=0.25, window=8.0, photons=5_000, seed=3, chunk_points=16
        )
        for old in OUT.glob("scale_out_acq_*.zarr"):  # this script's own stores: a rerun must not resume
            shutil.rmtree(old)
        t = time.perf_counter()
        here = acquire_planar(vol, setup, OUT / "scale_out_acq_threads.zarr", overwrite=True)
        report["acquire_threads_s"] = time.perf_counter() - t
        for n in (1, 2):
            with open_cluster(f"local:{n}") as cluster:
                warm_setup = PlanarSetup(**{**setup.__dict__, "grid": (2, 2), "photons": 100})
                acquire_planar(
                    vol, warm_setup, OUT / "scale_out_acq_warm.zarr", overwrite=True, scheduler=cluster
                )
                t = time.perf_counter()
                there = acquire_planar(
                    vol, setup, OUT / f"scale_out_acq_{n}.zarr", overwrite=True, scheduler=cluster
                )
                report[f"acquire_local{n}_s"] = time.perf_counter() - t
                report[f"acquire_local{n}_identical"] = bool(np.array_equal(here["R_d"], there["R_d"]))
        report["acquire_speedup_2w_over_1w"] = report["acquire_local1_s"] / report["acquire_local2_s"]
    report["load_after"] = os.getloadavg()
    name = "scale_out.json"
    if args.skip_fit:
        name = "scale_out_acquire.json"
    elif args.skip_acquire:
        name = f"scale_out_fit_{args.copies}.json"
    (OUT / name).write_text(json.dumps(report, indent=1))
    for key, value in report.items():
        print(f"{key:40s} {value}")


if __name__ == "__main__":
    main()
