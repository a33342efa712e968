"""Start-up of the command line: ``translucency --help``, ``translucency info`` and ``import translucency``.

Each command runs in a fresh interpreter, several times; the table gives the median wall time and the
median CPU time (user + system of the child) of each.  Wall time depends on how busy the machine is, CPU
time much less.  Two baselines are measured in the same run:

* the engines the commands used to import before they loaded them only where used (NumPy, Zarr, Dask,
  distributed, Matplotlib, Numba, SciPy, trimesh, scikit-image): a yardstick of this machine's speed;
* with ``--before REV``: the same commands on that git revision's ``src/`` (extracted with ``git archive``
  into a temporary folder), and the ratio before / now.

    python benchmarks/startup.py                 # this tree, and the engines' import as the yardstick
    python benchmarks/startup.py --before 0ab5950 --runs 7

The model file ``info`` reads is a small planar model written here (one point, one term); the data set is
the embedded default scan.  Target: ``--help`` and ``info`` under 1 s on a quiet machine.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: the console script (``translucency = translucency.cli.app:main``), run as the entry point runs it
CLI = "import sys; from translucency.cli.app import main; sys.argv[0] = 'translucency'; sys.exit(main())"

#: the engines the command tree imported before it loaded them only where used
ENGINES = (
    "import numpy, zarr, dask, distributed, matplotlib.image, numba, scipy.optimize, trimesh, skimage.measure"
)


def timed(argv: list[str], src: Path, runs: int) -> tuple[float, float]:
    """Median wall and CPU seconds (user + system of the child) of ``argv`` run ``runs`` times."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(src), os.environ.get("PYTHONPATH", "")])}
    walls, cpus = [], []
    for _ in range(runs):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t = time.perf_counter()
        subprocess.run(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        walls.append(time.perf_counter() - t)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return statistics.median(walls), statistics.median(cpus)


def import_times(src: Path, module: str, top: int) -> tuple[float, list[tuple[str, float]]]:
    """``import module``'s cumulative import time (s, ``python -X importtime``) and the ``top`` largest
    of the outside packages it loads (their top-level modules), largest first."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(src), os.environ.get("PYTHONPATH", "")])}
    res = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", f"import {module}"],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    found, total = {}, 0.0
    for line in res.stderr.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        _, cumulative, name = (part.strip() for part in line.split("|", 2))
        seconds = int(cumulative) / 1e6
        if name == module:
            total = seconds
        elif "." not in name and not name.startswith(("_", "translucency")):
            found[name] = max(found.get(name, 0.0), seconds)
    return total, sorted(found.items(), key=lambda kv: -kv[1])[:top]


def small_model(folder: Path) -> Path:
    """A planar model file of one incident point and one term (R_d = 0.05 e^{-r} mm⁻²)."""
    from translucency.io.model_file import save_model
    from translucency.model import ExponentialModel, PlanarAlpha

    alpha = PlanarAlpha.uniform((8, 8), pitch=0.5)
    model = ExponentialModel(np.zeros((1, 2)), [[[[0.05]]]], [[[[-1.0]]]], alpha, s_g=[1.0], s_b=[1.0])
    return save_model(model, folder / "small.model.zip")


def old_tree(rev: str, folder: Path) -> Path:
    """``src/`` of git revision ``rev``, extracted into ``folder``."""
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", rev, "src"], capture_output=True, check=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder / "src"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5, help="fresh processes per command (median)")
    parser.add_argument("--before", metavar="REV", help="also time git revision REV's src/ (and the ratio)")
    args = parser.parse_args()

    from translucency.data import default_dataset_path

    py = sys.executable
    with tempfile.TemporaryDirectory() as tmp:
        model = small_model(Path(tmp))
        commands = {
            "translucency --help": [py, "-c", CLI, "--help"],
            "translucency fit --help": [py, "-c", CLI, "fit", "--help"],
            "translucency info MODEL": [py, "-c", CLI, "info", str(model)],
            "translucency info DATASET": [py, "-c", CLI, "info", str(default_dataset_path())],
            "import translucency": [py, "-c", "import translucency"],
            "python (nothing imported)": [py, "-c", "pass"],
        }
        trees = {"now": ROOT / "src"}
        if args.before:
            trees[f"before ({args.before})"] = old_tree(args.before, Path(tmp))
        load = os.getloadavg()[0]
        print(
            f"start-up: median of {args.runs} fresh processes, wall / CPU (user + system) seconds; "
            f"load average {load:.1f} on {os.cpu_count()} cores"
        )
        width = max(map(len, commands)) + 2
        print(
            "".ljust(width)
            + "".join(f"{name:>22}" for name in trees)
            + ("   before/now (CPU)" if args.before else "")
        )
        for what, argv in commands.items():
            cells, cpus = [], []
            for src in trees.values():
                wall, cpu = timed(argv, src, args.runs)
                cells.append(f"{wall:8.2f} / {cpu:5.2f} s")
                cpus.append(cpu)
            ratio = f"   {cpus[1] / max(cpus[0], 1e-3):6.1f}x" if args.before else ""
            print(what.ljust(width) + "".join(f"{c:>22}" for c in cells) + ratio)
        wall, cpu = timed([py, "-c", ENGINES], ROOT / "src", args.runs)
        print(f"{'yardstick: import the engines':{width}}{f'{wall:8.2f} / {cpu:5.2f} s':>22}")
        print("  (numpy, zarr, dask, distributed, matplotlib.image, numba, scipy.optimize, trimesh, skimage)")
        for name, src in trees.items():
            total, tops = import_times(src, "translucency.cli.app", 8)
            listed = ", ".join(f"{mod} {sec:.2f}" for mod, sec in tops)
            print(f"import translucency.cli.app ({name}): {total:.2f} s (-X importtime); largest: {listed}")


if __name__ == "__main__":
    main()
