"""Objects against a converged reference: the main job's pig, by number of incident points at an equal
photon budget, with and without the measured near field (issue 12's error budget, partly).

Run: ``python benchmarks/objects_error.py [--configs 96x8000,384x2000,1536x500]``.  Uses the shipped
(or cached) converged reference of Figure 2 (``make default-reference``); prints one row per
configuration — relative RMSE and FLIP against the reference, mean brightness ratio, and the reference's
own noise — and writes ``objects_error.json`` beside the data it makes (``--work``).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from translucency.acquire.mesh import acquire_mesh
from translucency.fit.mesh import fit_mesh
from translucency.mitsuba import mesh_scene
from translucency.pipeline import FIGURE2_REFERENCE_SPP, figure2_scene
from translucency.render.compare import compare
from translucency.render.picture import VertexPicture, coverage
from translucency.render.reference import converged_reference
from translucency.transport.matrices import transport_matrices
from translucency.transport.relight import relight_object


def render(model, mesh, light, camera, scene):
    L, _, _ = relight_object(
        transport_matrices(model, mesh, through=False), mesh, scene, light, camera.origin
    )
    return VertexPicture(mesh, camera, spp=16).draw(L)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument(
        "--configs", default="96x8000,384x2000,1536x500", help="points x photons, comma-separated"
    )
    ap.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="objects_error_")))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--max-rate", type=float, default=None, help="steepest fitted |d|, 1/mm (default: the fit's)"
    )
    args = ap.parse_args()
    mesh, volume, light, camera = figure2_scene()
    mask = coverage(mesh, camera)
    reference, info = converged_reference(mesh, volume, light, camera, mask, spp=FIGURE2_REFERENCE_SPP)
    scene = mesh_scene(mesh)
    print(
        f"reference: 2 x {info['spp']} spp volpath, own noise {info['noise']:.4f} (cache: {info['cached']})"
    )
    print(
        f"{'points x photons':>18} {'near field':>11} {'rel RMSE':>9} {'FLIP':>6} {'brightness':>10} {'s':>6}"
    )
    rows = []
    for cfg in args.configs.split(","):
        points, photons = (int(v) for v in cfg.split("x"))
        t = time.perf_counter()
        data = acquire_mesh(
            mesh,
            volume,
            args.work / f"pig_{cfg}_{args.seed}.zarr",
            n_points=points,
            photons=photons,
            chunk_points=32,
            index_matched=True,
            seed=args.seed,
        )
        fit = fit_mesh(data, "iso", max_rate=args.max_rate)
        seconds = time.perf_counter() - t
        for near in ("measured", "profile"):
            model = fit.model
            saved = model.measured
            if near == "profile":
                model.measured = None
            ours = render(model, mesh, light, camera, scene)
            model.measured = saved
            cmp = compare(reference, ours, mask)
            row = {
                "points": points,
                "photons": photons,
                "near_field": near,
                "rel_rmse": cmp["rel_rmse"],
                "flip": cmp["flip_mean_object"],
                "brightness": float(ours[mask].mean() / reference[mask].mean()),
                "seconds": seconds,
            }
            rows.append(row)
            print(
                f"{cfg:>18} {near:>11} {row['rel_rmse']:9.3f} {row['flip']:6.3f} {row['brightness']:10.3f} "
                f"{seconds:6.0f}"
            )
    (args.work / "objects_error.json").write_text(json.dumps({"reference": info, "rows": rows}, indent=2))
    print(f"written: {args.work / 'objects_error.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
