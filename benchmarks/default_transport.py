"""Which transport should ``render`` draw by default?  The paper's radial profile against the same profile
with the through-body table, on today's data and fit defaults (the unscattered light apart, a fall-off per
channel), each against a converged volpath reference.

For each case one acquisition (``acquire mesh``'s defaults, seed 3; a data set already in ``--work`` is
read again), one fit (``fit``'s defaults: it stores the through-body table in the model), and the object
drawn twice by ``render``'s chain — ``transport_matrices(model, mesh, through=False)`` (``render --paper``)
and ``through=True`` (``render``'s default) — beside the reference (relative RMSE, FLIP, brightness, each
region's brightness, the unlit side's hue):

    python benchmarks/default_transport.py --meshes ../shared/meshes --spp 2304 --case CASE [--case CASE ...]

``--held-out`` also evaluates both against another acquisition of the same points (``evaluate --truth``,
with ``--paper`` for the paper's profile).

Cases as in ``unscattered.py`` (``name:mesh:mm per unit:up:material:points:photons:light:view``, or
``pig``).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from translucency import evaluate_report, load_model, save_model
from translucency.acquire.mesh import acquire_mesh
from translucency.fit.mesh import fit_mesh
from translucency.mitsuba import mesh_scene
from translucency.render.compare import compare, region_errors
from translucency.render.picture import VertexPicture, coverage
from translucency.render.reference import converged_reference
from translucency.render.tonemap import auto_exposure, save_images
from translucency.transport import PreparedObject, TransportOptions
from unscattered import scene_of

#: the transports compared, by kind name (``TransportOptions(kind=...)``), as ``render`` draws them
KINDS = ("paper", "default", "walked")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument("--case", action="append", required=True, help="a case spec (unscattered.py) or pig")
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel of each of the two references")
    ap.add_argument("--size", type=int, nargs=2, default=(128, 96))
    ap.add_argument("--kinds", default=",".join(KINDS), help="the transports drawn, by name")
    ap.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="default_transport_")))
    ap.add_argument(
        "--held-out",
        action="store_true",
        help="also evaluate both transports against another acquisition (seed 4, 4x the photons, same "
        "filling): evaluate --truth and evaluate --truth --paper",
    )
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    out = []
    for case in args.case:
        name, P, N, mesh, volume, light, camera, spp = scene_of(case, args.meshes, args.size)
        mask = coverage(mesh, camera)
        reference, info = converged_reference(mesh, volume, light, camera, mask, spp=spp or args.spp)
        exposure = auto_exposure(reference, mask)
        save_images(reference, args.work / f"{name}_reference", exposure)
        scene = mesh_scene(mesh)
        picture = VertexPicture(mesh, camera, spp=16, light=light)
        t = time.perf_counter()
        data = acquire_mesh(
            mesh, volume, args.work / f"{name}_{P}x{N}_apart.zarr", n_points=P, photons=N, seed=3,
            chunk_points=32, index_matched=True,
        )  # fmt: skip
        t_acquire = time.perf_counter() - t
        model_path = args.work / f"{name}_{P}x{N}.model.zip"
        if model_path.is_file():  # this script's own fit of an earlier run
            model = load_model(model_path)
        else:
            model = fit_mesh(data, "iso").model
            save_model(model, model_path)
        if args.held_out:
            _held_out(args.work, name, mesh, volume, data, model, P, N)
        for label in args.kinds.split(","):
            prepared = PreparedObject(model, mesh, eta=1.0, options=TransportOptions(kind=label))
            t = time.perf_counter()
            L, E = prepared.relight(light, camera.origin, scene)
            t_draw = time.perf_counter() - t
            ours = picture.draw(L)
            save_images(ours, args.work / f"{name}_{label}", exposure)
            cmp = compare(reference, ours, mask)
            regions = region_errors(mesh, scene, camera, E, reference, ours, mask)
            row = {
                "case": name,
                "transport": label,
                "rel_rmse": cmp["rel_rmse"],
                "flip": cmp["flip_mean_object"],
                "brightness": float(ours[mask].mean() / reference[mask].mean()),
                "regions": {k: v["brightness"] for k, v in regions.items()},
                "unlit_hue": regions["unlit"]["colour"],
                "reference_noise": info["noise"],
                "acquire_s": t_acquire,
                "relight_s": t_draw,
            }
            out.append(row)
            by_region = " ".join(f"{k} {v:.2f}x" for k, v in row["regions"].items() if k != "all")
            print(
                f"{name:<22} {label:<8} rel RMSE {row['rel_rmse']:.3f}  FLIP {row['flip']:.3f}  "
                f"brightness {row['brightness']:.3f}  ({by_region}, {t_draw:.1f} s)  unlit hue "
                f"{np.round(row['unlit_hue'], 2).tolist()}  noise {info['noise']:.3f}",
                flush=True,
            )
    (args.work / "default_transport.json").write_text(json.dumps(out, indent=2))
    print(f"written: {args.work / 'default_transport.json'}")
    return 0


def _held_out(work: Path, name: str, mesh, volume, data: Path, model, P: int, N: int) -> None:
    """``evaluate --truth`` with both transports: relative L2 per pair against another acquisition of the
    same points (seed 4, 4 N photons), the truth's own noise beside."""
    truth = acquire_mesh(
        mesh, volume, work / f"{name}_{P}x{4 * N}_truth.zarr", n_points=P, photons=4 * N, seed=4,
        chunk_points=32, index_matched=True,
    )  # fmt: skip
    path = work / f"{name}.model.zip"
    path.unlink(missing_ok=True)  # (this script's own file of an earlier run)
    save_model(model, path)
    for label, paper in (("paper's profile", True), ("profile x through-body table", False)):
        report = work / f"{name}_held_{'paper' if paper else 'default'}"
        h = evaluate_report(path, data, truth=truth, report=report, paper=paper, overwrite=True).summary
        print(f"{name:<22} {label:<30} held out: rel L2 {h['rel_l2']:.4f}"
              f"  (the truth's noise {h['noise_floor']['all']:.4f})", flush=True)  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
