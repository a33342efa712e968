"""Objects outside the default case: meshes × materials × lights against converged references.

Each case acquires a mesh per vertex, fits the isotropic model as ``fit`` does by default (its structure
chosen by held-out error) and renders it beside the mean of two independent volpath renders (their noise
measured; cached under ~/.cache/translucency), and prints the relative RMSE, FLIP, brightness and the error
by region, once for each incidence law (``half-space``, the render's default, in and out;
``half-space-in``, the irradiance only; ``normal``, the data's own: :mod:`translucency.model.incidence`),
and the through-body extension beside them (``half-space+through``, :mod:`translucency.model.through`).
With ``--compare structure`` it renders, instead, three fits of the same data as ``render`` draws them by
default (half-space, through-body table): the default, the fixed iso n = 3 with a fall-off per channel,
and the paper's choice (iso n = 3, shared colour) — that one also as the paper draws it (``render
--paper``).  Meshes are the users' files, e.g. ``../shared/meshes``:

    python benchmarks/objects_table.py --meshes ../shared/meshes
    python benchmarks/objects_table.py --meshes ../shared/meshes --size 128 96 --compare structure

A case is ``name:mesh file:mm per unit:up axis:material:points:photons:light:view`` (``--case``, repeatable);
the default cases need ``cow.obj``, ``stanford-bunny.obj`` and ``spot.obj`` in ``--meshes``.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from translucency.acquire.mesh import acquire_mesh, object_volume
from translucency.fit.mesh import fit_mesh
from translucency.io.mesh import load_mesh
from translucency.mitsuba import mesh_scene
from translucency.model.incidence import INCIDENCE_LAWS
from translucency.render.camera import Camera
from translucency.render.compare import compare, region_errors
from translucency.render.lights import parse_light
from translucency.render.picture import VertexPicture, coverage
from translucency.render.reference import converged_reference
from translucency.transport.matrices import transport_matrices
from translucency.transport.relight import relight_object

CASES = [
    "cow-skin-spot:cow.obj:8:z:skin:128:4000:spot:-60,70,90,0,0,0,25,3e4:-1,1.2,0.6",
    "bunny-marble-directional:stanford-bunny.obj:400:y:marble:128:4000:directional:-0.3,0.4,-1,1:1,-1.6,0.7",
    "spot-skin-sky:spot.obj:30:y:skin:128:4000:env:0.05:1,-1.6,0.7",
    "spot-marble-spot:spot.obj:20:y:marble:128:4000:spot:50,-80,40,0,0,0,25,3e4:1,-1.6,0.7",
    "cow-apple-point:cow.obj:4:z:apple-slice:128:4000:point:-30,35,45,8e3:-1,1.2,0.6",
]


#: --compare structure: label -> (fit_mesh arguments, through-body table)
STRUCTURES = {
    "default": ({}, True),
    "iso n=3 per-channel": (dict(model="iso", n_terms=3, colour="per-channel"), True),
    "paper's choice (iso n=3 shared)": (dict(model="iso", n_terms=3, colour="shared"), True),
    "paper's choice, render --paper": (dict(model="iso", n_terms=3, colour="shared"), False),
}


def run_case(spec: str, meshes: Path, work: Path, spp: int, size, compare: str = "laws") -> dict:
    name, file, scale, up, material, points, photons, kind, light, view = spec.split(":")
    mesh = load_mesh(meshes / file, scale_mm=float(scale), up=up)
    volume = object_volume(material, mesh, 1.0, seed=3)
    t = time.perf_counter()
    data = acquire_mesh(
        mesh,
        volume,
        work / f"{name}.zarr",
        n_points=int(points),
        photons=int(photons),
        seed=3,
        chunk_points=32,
        index_matched=True,
    )
    fit = fit_mesh(data)  # as `fit` does by default
    t_fit = time.perf_counter() - t
    light = parse_light(f"{kind}:{light}")
    camera = Camera.looking_at(mesh, [float(v) for v in view.split(",")], *size)
    mask = coverage(mesh, camera)
    scene = mesh_scene(mesh)
    T = transport_matrices(fit.model, mesh, through=False)
    picture = VertexPicture(mesh, camera, spp=16, light=light)
    reference, info = converged_reference(mesh, volume, light, camera, mask, spp=spp)
    row = {
        "case": name,
        "vertices": len(mesh.vertices),
        "extent_mm": float(np.linalg.norm(mesh.extents)),
        "reference_noise": info["noise"],
        "reference_spp": spp,
        "acquire_fit_s": t_fit,
        "reference_s": info["seconds"],
    }
    if compare == "structure":  # three fits of the same data, as render draws each by default
        row["chosen"] = fit.options["structure"]["chosen"]["label"]
        fits = {}
        for label, (kw, through) in STRUCTURES.items():
            key = json.dumps(kw, sort_keys=True)
            fits[key] = fits.get(key) or (fit if not kw else fit_mesh(data, **kw))
            T = transport_matrices(fits[key].model, mesh, through=through)
            row[label] = _scores(T, mesh, scene, light, camera, picture, reference, mask, "half-space")
        return row
    # the paper's model under each incidence law, then the through-body extension (model/through.py)
    variants = [(name_of_law, T, name_of_law) for name_of_law in INCIDENCE_LAWS]
    variants.append(("half-space+through", transport_matrices(fit.model, mesh, through=True), "half-space"))
    for name_of_law, transport, law in variants:
        row[name_of_law] = _scores(transport, mesh, scene, light, camera, picture, reference, mask, law)
    return row


def _scores(transport, mesh, scene, light, camera, picture, reference, mask, law) -> dict:
    """The picture of ``transport`` under ``law`` against the reference: overall and by region."""
    L, E, _ = relight_object(transport, mesh, scene, light, camera.origin, incidence=law)
    ours = picture.draw(L)
    cmp = compare(reference, ours, mask)
    regions = region_errors(mesh, scene, camera, E, reference, ours, mask)
    return {
        "rel_rmse": cmp["rel_rmse"],
        "flip": cmp["flip_mean_object"],
        "brightness": float(ours[mask].mean() / reference[mask].mean()),
        "regions": {k: v["rel_rmse"] for k, v in regions.items()},
        "region_brightness": {k: v["brightness"] for k, v in regions.items()},
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument("--case", action="append", help="a case spec (module docstring); default: three cases")
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel of each of the two references")
    ap.add_argument("--size", type=int, nargs=2, default=(160, 120))
    ap.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="objects_table_")))
    ap.add_argument("--compare", choices=("laws", "structure"), default="laws",
                    help="laws: the default fit under each incidence law; structure: three fits")  # fmt: skip
    ap.add_argument("--out", type=Path, default=None,
                    help="--compare structure: a Markdown page to write the table into")  # fmt: skip
    ap.add_argument("--from-json", type=Path, default=None, help="Only write the table from this JSON.")
    args = ap.parse_args()
    if args.from_json is not None:
        _write_structure_table(json.loads(args.from_json.read_text()), args)
        return 0
    rows = []
    columns = [*INCIDENCE_LAWS, "half-space+through"] if args.compare == "laws" else list(STRUCTURES)
    for spec in args.case or CASES:
        row = run_case(spec, args.meshes, args.work, args.spp, tuple(args.size), args.compare)
        rows.append(row)
        if "chosen" in row:
            print(f"{row['case']:<28} the default chose {row['chosen']}", flush=True)
        for law in columns:
            r = row[law]
            worst = max(r["regions"].items(), key=lambda kv: kv[1] if np.isfinite(kv[1]) else -1)
            print(
                f"{row['case']:<28} {law:<10} rel RMSE {r['rel_rmse']:.3f}  FLIP {r['flip']:.3f}  brightness "
                f"{r['brightness']:.3f}  reference noise {row['reference_noise']:.3f}  regions "
                + " ".join(f"{k} {v:.3f} ({r['region_brightness'][k]:.2f}x)" for k, v in r["regions"].items())
                + f"  (worst {worst[0]})",
                flush=True,
            )
    (args.work / "objects_table.json").write_text(json.dumps(rows, indent=2))
    print(f"written: {args.work / 'objects_table.json'}")
    if args.compare == "structure":
        _write_structure_table(rows, args)
    return 0


def _write_structure_table(rows: list, args) -> None:
    """The --compare structure table (printed; with --out written into that page's own section)."""
    from accuracy_table import write_between_markers  # the benchmarks' shared page writer

    def cell(r: dict) -> str:
        return f"{r['rel_rmse']:.3f} / {r['flip']:.3f} / {r['brightness']:.3f}"

    lines = [
        "Each cell: relative RMSE / FLIP / brightness (ours over the reference's) against the mean of two "
        # the commands are in the page's own "Reproducing these measurements" section, after the table
        "256-spp volpath renders (the benchmark of this page, [Reproducing these measurements]"
        "(#reproducing-these-measurements), with the specs below; 128 incident points × 4,000 photons, "
        "index-matched, 1 mm voxels, seed 3). The first three columns are drawn as `render` draws by "
        "default (half-space incidence, through-body table); the last is the paper's choice drawn as the "
        "paper does (`render --paper`).",
        "",
        "| case | vertices | default chose | default | iso n=3 per channel | paper's choice (iso n=3 shared) "
        "| paper's choice, `render --paper` | reference noise |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for row in rows:
        cells = " | ".join(cell(row[label]) for label in STRUCTURES)
        noise = row["reference_noise"]
        lines.append(f"| {row['case']} | {row['vertices']:,} | {row['chosen']} | {cells} | {noise:.3f} |")
    text = "\n".join([*lines, ""])
    print(text)
    if args.out:
        write_between_markers(args.out, text, "benchmarks/objects_table.py --compare structure")


if __name__ == "__main__":
    raise SystemExit(main())
