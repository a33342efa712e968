"""A lab's scan end to end on this machine: every stage's time and peak memory beside the estimate the
command prints before its work, and what each stage writes.

    python benchmarks/large_scan.py WORK [--voxel 0.37] [--subdivide 1] [--points 64] [--photons 2000]

The mesh is the procedural pig at ``--voxel`` mm (``make_pig``), subdivided ``--subdivide`` times at its
edges' midpoints (the same shape at a lab's resolution: 0.37 mm and once gives 337,714 vertices, twice
1.35 M).  The stages are the command line's, each its own process (``python -m translucency ... --json``):
``acquire mesh`` (index-matched marble), ``fit``, ``render`` (320 x 240, the default light), ``render
--scene`` (benchmarks/scenes.py's pig scene at 160 x 120), ``view --export``, ``export --gltf``.  Peak
memory is the resident set of the stage's process tree, sampled every 0.2 s; a stage above
``--kill-gb`` is stopped and reported as such (so that one stage cannot take the machine).  A stage's
outputs are kept in WORK and re-used (``--fresh`` starts again).  One table at the end, and
``WORK/large_scan.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from scenes import scene_folder  # noqa: E402 — the benchmark's own scenes

TL = [sys.executable, "-m", "translucency"]


def _tree_rss(pid: int) -> int:
    """Resident bytes of ``pid`` and its descendants (Linux /proc)."""
    total, stack = 0, [pid]
    while stack:
        p = stack.pop()
        try:
            with open(f"/proc/{p}/status") as f:
                for line in f:
                    if line.startswith("VmRSS:"):
                        total += int(line.split()[1]) * 1024
            with open(f"/proc/{p}/task/{p}/children") as f:
                stack += [int(c) for c in f.read().split()]
        except (FileNotFoundError, ProcessLookupError, ValueError):
            continue
    return total


def run_stage(name: str, args: list[str], kill_bytes: float) -> dict:
    """Run one command; its seconds, peak memory, its own estimate (``--json``) and how it ended."""
    t = time.perf_counter()
    proc = subprocess.Popen(TL + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    peak, killed = [0], [False]

    def watch():
        while proc.poll() is None:
            rss = _tree_rss(proc.pid)
            peak[0] = max(peak[0], rss)
            if rss > kill_bytes:
                killed[0] = True
                os.kill(proc.pid, signal.SIGKILL)
            time.sleep(0.2)

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    out, err = proc.communicate()
    watcher.join()
    row = {"stage": name, "seconds": time.perf_counter() - t, "peak_bytes": peak[0], "rc": proc.returncode}
    if killed[0]:
        row["ended"] = f"stopped above {kill_bytes / 1e9:.0f} GB"
    elif proc.returncode != 0:
        row["ended"] = (err.strip().splitlines() or ["(no message)"])[-1]
    try:
        summary = json.loads(out.strip().splitlines()[-1]) if out.strip() else {}
    except json.JSONDecodeError:
        summary = {}
    estimate, time_estimate = summary.get("estimate") or {}, summary.get("time_estimate") or {}
    row["estimate_bytes"] = estimate.get("memory_bytes")
    row["estimate_seconds"] = time_estimate.get("seconds")
    row["estimate_source"] = time_estimate.get("source")
    row["summary"] = summary
    print(_line(row), flush=True)
    return row


def _line(row: dict) -> str:
    est = []
    if row.get("estimate_seconds") is not None:
        calibrated = "" if str(row.get("estimate_source", "")).startswith("calibrated") else " (uncalibrated)"
        est.append(f"{row['estimate_seconds']:.0f} s{calibrated}")
    if row.get("estimate_bytes") is not None:
        est.append(f"{row['estimate_bytes'] / 2**30:.1f} GiB")
    return (
        f"| {row['stage']} | {row['seconds']:.0f} s | {row['peak_bytes'] / 1e9:.1f} GB | "
        f"{', '.join(est) or '—'} | {row.get('ended', 'ok')} |"
    )


def _mesh(work: Path, voxel: float, subdivide: int) -> Path:
    import trimesh

    from translucency.acquire.objects import make_pig
    from translucency.mitsuba import write_ply

    path = work / f"pig_{voxel:g}_x{subdivide}.ply"
    if not path.exists():
        mesh = make_pig(voxel)
        for _ in range(subdivide):
            mesh = trimesh.Trimesh(*trimesh.remesh.subdivide(mesh.vertices, mesh.faces), process=False)
        write_ply(path, mesh.vertices, mesh.faces)
    return path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("work", type=Path)
    ap.add_argument("--voxel", type=float, default=0.37)
    ap.add_argument("--subdivide", type=int, default=1)
    ap.add_argument("--points", type=int, default=64)
    ap.add_argument("--photons", type=int, default=2000)
    ap.add_argument("--kill-gb", type=float, default=20.0)
    ap.add_argument("--fresh", action="store_true")
    ap.add_argument("--skip", action="append", default=[], help="a stage to leave out (repeat)")
    args = ap.parse_args()
    work = args.work
    work.mkdir(parents=True, exist_ok=True)
    mesh = _mesh(work, args.voxel, args.subdivide)
    data, model = work / "scan.zarr", work / "scan.model.zip"
    kill = args.kill_gb * 1e9
    rows = []
    print("| stage | time | peak memory | its estimate | ended |", flush=True)
    print("| --- | --- | --- | --- | --- |", flush=True)
    if args.fresh or not (data / "zarr.json").exists():
        acquire = ["acquire", "mesh", "--mesh", str(mesh), "--out", str(data), "--material", "marble"]
        acquire += ["--points", str(args.points), "--photons", str(args.photons), "--index-matched"]
        rows.append(run_stage("acquire mesh", acquire + ["--seed", "3", "--overwrite", "--json"], kill))
    if args.fresh or not model.exists():
        rows.append(run_stage("fit", ["fit", str(data), "--out", str(model), "--overwrite", "--json"], kill))
    stages = {
        "render": ["render", str(model), "--out", str(work / "render"), "--overwrite", "--json"],
        "view --export": ["view", str(model), "--export", str(work / "page"), "--overwrite", "--json"],
        "export --gltf": ["export", str(model), "--gltf", str(work / "scan.glb"), "--overwrite", "--json"],
    }
    for name, command in stages.items():
        if name not in args.skip:
            rows.append(run_stage(name, command, kill))
    if "render scene" not in args.skip:
        scene = scene_folder("pig", work / "scene", model, (160, 120))
        command = ["render", "scene", str(scene), "--object", f"object={model}", "--out", str(work / "lit")]
        rows.append(run_stage("render scene", command + ["--overwrite", "--json"], kill))
    page = [p for p in (work / "page").glob("*") if p.name != ".translucency-output.json"]
    sizes = {
        "model file": model.stat().st_size if model.exists() else None,
        "glTF": (work / "scan.glb").stat().st_size if (work / "scan.glb").exists() else None,
        "page": sum(p.stat().st_size for p in page) if page else None,
    }
    print(f"vertices: {_vertices(model):,}", flush=True)
    for what, size in sizes.items():
        if size is not None:
            print(f"{what}: {size / 1e6:.2f} MB", flush=True)
    record = {"args": {k: str(v) for k, v in vars(args).items()}, "stages": rows, "sizes_bytes": sizes}
    (work / "large_scan.json").write_text(json.dumps(record, indent=2, default=str))
    return 0


def _vertices(model: Path) -> int:
    from translucency.io.model_file import load_model

    return len(load_model(model).alpha.values) if model.exists() else 0


if __name__ == "__main__":
    raise SystemExit(main())
