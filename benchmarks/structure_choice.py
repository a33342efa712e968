"""Does the fit's default structure (chosen by held-out error on the data's own photons) lose to a fixed one?

For every sample of docs/accuracy.md (40,000 photons a point, truth 3×) and two kept aside for this check
— a homogeneous potato at 20,000 photons and a fibrous volume of another seed at 20,000 photons, each
against an independent 400,000-photon acquisition — the default fit and every fixed structure it could
have chosen (isotropic with per-channel or shared colour, anisotropic with m = 2, 4, 8, 16, and the
paper's m = 8 with shared colour) are fitted to the data and scored against the truth (relative L2 over
all pairs, the truth's noise beside).  Then the choice's cost: the default fit, the chosen structure
fitted directly and the isotropic fit, timed side by side on the demo's data set (1,024 points), with
ratios.  Writes a section of docs/accuracy.md.

    python benchmarks/structure_choice.py --out docs/accuracy.md
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from accuracy_table import SAMPLES, acquire, pct, write_between_markers
from translucency.data import default_dataset_path
from translucency.evaluate.errors import finite_or_null, planar_errors
from translucency.fit.mesh import fit_mesh
from translucency.fit.planar import fit_planar
from translucency.fit.structure import selection_points
from translucency.io.datasets import open_any_dataset
from translucency.io.mesh_dataset import MeshDataset

#: (sample, volume seed, photons, truth photons): the table's seven, and the two kept for this check
KEPT = [("homogeneous:potato", 1, 20_000, 400_000), ("fibers", 2, 20_000, 400_000)]
FIXED = {  # label -> fit_planar arguments: what the default could have chosen
    "iso": dict(model="iso"),
    "iso shared": dict(model="iso", colour="shared"),
    **{f"aniso m={m}": dict(model="aniso", n_directions=m) for m in (2, 4, 8, 16)},
    "aniso m=8 shared (the paper's)": dict(model="aniso", n_directions=8, colour="shared"),
}
PAPER = "aniso m=8 shared (the paper's)"


def score(ds: Path, truth: Path) -> dict:
    """Every fit of ``ds`` against ``truth``: held-out error, the default's choice and seconds."""
    out = {}
    for label, kw in {"default": {}, **FIXED}.items():
        t = time.perf_counter()
        fit = fit_planar(ds, **kw)
        seconds = time.perf_counter() - t
        err = planar_errors(fit.model, truth, flagged=fit.flagged)
        out[label] = {"rel_l2": err.rel_l2, "noise": err.noise["all"], "seconds": seconds}
        if label == "default":
            out[label]["chosen"] = fit.options["structure"]["chosen"]["label"]
        print(f"  {label:32s} {100 * err.rel_l2:6.2f} %  ({seconds:.2f} s)", flush=True)
    return out


def timing(repeats: int, ds=None) -> dict:
    """Median seconds of the default fit, the chosen structure fitted directly, and iso n = 3, on ``ds`` (a
    planar or mesh data set; default the demo's planar data), after one warm-up of each so that
    compiled kernels are loaded."""
    ds = ds or default_dataset_path()
    on_mesh = isinstance(open_any_dataset(ds), MeshDataset)
    fit = fit_mesh if on_mesh else fit_planar
    chosen = fit(ds).options["structure"]["chosen"]
    alone = dict(model=chosen["model"], n_terms=chosen["n_terms"], colour=chosen["colour"])
    if not on_mesh:
        alone["n_directions"] = max(2, chosen["n_directions"])
    runs = {
        "default (choice + fit)": {},
        f"chosen structure alone ({chosen['label']})": alone,
        "iso n=3 alone": dict(model="iso", n_terms=3),
    }
    out = {}
    for label, kw in runs.items():
        fit(ds, **kw)  # warm-up
        times = []
        for _ in range(repeats):
            t = time.perf_counter()
            fit(ds, **kw)
            times.append(time.perf_counter() - t)
        out[label] = float(np.median(times))
        print(f"  {label:48s} {out[label]:.2f} s", flush=True)
    return out


def markdown(results: dict, times: dict, args) -> str:
    rows = []
    met_all = True
    for sample, fits in results.items():
        default, fixed = fits["default"], {k: v for k, v in fits.items() if k != "default"}
        best = min(fixed, key=lambda k: fixed[k]["rel_l2"])
        noise = default["noise"]
        gap = default["rel_l2"] - fixed[best]["rel_l2"]
        over_iso = default["rel_l2"] - fixed["iso"]["rel_l2"]
        met = gap <= noise and over_iso <= noise
        met_all &= met
        rows.append(
            f"| {sample} | {default['chosen']} | {pct(default['rel_l2'])} | "
            f"{best} {pct(fixed[best]['rel_l2'])} "
            f"| {100 * gap:+.2f} | {pct(fixed['iso']['rel_l2'])} | {pct(fixed['aniso m=8']['rel_l2'])} | "
            f"{pct(fixed[PAPER]['rel_l2'])} | {pct(noise)} | "
            f"{'**met**' if met else '**not met**'} |"
        )
    (d_label, d), (c_label, c), (i_label, i) = times["planar"].items()
    return "\n".join(
        [
            "## The default's structure against every fixed one (held-out)",
            "",
            # the command is in the page's own "Reproducing these measurements" section, at its end
            "Measured by the structure benchmark of this page, "
            "[Reproducing these measurements](#reproducing-these-measurements) "
            f"({args.photons:,}-photon data and a 3× truth for the table's samples; the two kept aside at "
            "20,000 photons against 400,000).  `fit` chooses the colour, n and m by held-out error on its "
            "own data (docs/fitting.md, *The structure*); each fixed structure is fitted too, and all are "
            "scored against the independent truth, % relative L2 over all pairs.  *gap*: the default minus "
            "the best fixed structure, percentage points.  Target: the default within the truth's noise of "
            "the best, and never worse than iso by more than that noise.",
            "",
            "| sample | default chose | default | best fixed | gap | iso | aniso m=8 | "
            "the paper's (m=8, shared) | truth noise | target |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
            *rows,
            "",
            f"Every sample: {'**met**' if met_all else '**not met**'}.",
            "",
            f"The choice's cost on the demo's data set (1,024 points, 33 × 33 pixels; median of "
            f"{args.repeats} after a warm-up, 2 CPU cores): {d_label} {d:.2f} s; {c_label} {c:.2f} s; "
            f"{i_label} {i:.2f} s.  Ratio **{d / c:.2f}×** the chosen structure's own fit, "
            f"**{d / i:.2f}×** the isotropic fit (target ≤ 2× one fit).",
            "",
            *mesh_cost(times.get("mesh"), args),
        ]
    )


def mesh_cost(times: dict | None, args) -> list[str]:
    """The choice's cost on a mesh data set, when one was timed (``--mesh-data``)."""
    if not times:
        return []
    (d_label, d), (c_label, c), (i_label, i) = times.items()
    return [
        f"On a mesh data set (`--mesh-data {args.mesh_data.name}`, {args.mesh_points} incident points, "
        f"{args.mesh_vertices:,} vertices; the candidates on {args.mesh_subset} of them): {d_label} "
        f"{d:.2f} s; {c_label} {c:.2f} s; {i_label} {i:.2f} s.  Ratio **{d / c:.2f}×** the chosen "
        f"structure's own fit, **{d / i:.2f}×** iso n = 3's.",
        "",
    ]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--photons", type=int, default=40_000, help="Photons of the table's fitted acquisitions.")
    ap.add_argument("--grid", type=int, default=5)
    ap.add_argument("--cache", type=Path, default=Path("bench_data"))
    ap.add_argument("--samples", default=",".join(SAMPLES))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument(
        "--mesh-data", type=Path, default=None, help="Also time the choice on this mesh data set."
    )
    ap.add_argument("--out", type=Path, default=None, help="Markdown file to write the section into.")
    args = ap.parse_args()
    args.cache.mkdir(parents=True, exist_ok=True)
    cases = [(s, 1, args.photons, 3 * args.photons) for s in args.samples.split(",") if s] + KEPT
    results = {}
    for sample, volume_seed, photons, truth_photons in cases:
        name = sample if volume_seed == 1 else f"{sample} (volume seed {volume_seed})"
        name += "" if photons == args.photons else f", {photons:,} photons (kept aside)"
        ds = acquire(sample, args.cache, photons, args.grid, 1, volume_seed)
        truth = acquire(sample, args.cache, truth_photons, args.grid, 2, volume_seed)
        print(name, flush=True)
        results[name] = score(ds, truth)
    print("timing", flush=True)
    times = {"planar": timing(args.repeats)}
    if args.mesh_data is not None:  # a mesh data set, e.g. a `make demo` folder's pig.zarr
        mesh = open_any_dataset(args.mesh_data)
        args.mesh_points, args.mesh_vertices = mesh.n_points, int(mesh.header["n_vertices"])
        args.mesh_subset = len(selection_points(mesh.n_points))
        times["mesh"] = timing(args.repeats, args.mesh_data)
    text = markdown(results, times, args)
    print(text)
    if args.out:
        write_between_markers(args.out, text, "benchmarks/structure_choice.py")
        path = args.out.with_name("structure_choice.json")
        path.write_text(json.dumps(finite_or_null({"results": results, "times": times}), indent=2) + "\n")


if __name__ == "__main__":
    main()
