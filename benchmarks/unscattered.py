"""The unscattered light in the tally: counted in R_d (the data sets made before) or kept apart (the default).

A photon that crosses a thin part without scattering leaves along the beam, a delta in direction that a
camera sees only head-on; counted in R_d it is drawn as diffuse exitance.  For each case the same walks
(one seed) are tallied both ways, fitted with the paper's shared colour and with a fall-off per channel,
and the object rendered by ``render``'s chain beside a converged volpath reference:

    python benchmarks/unscattered.py --meshes MESHES --spp 2304 --case CASE [--case CASE ...] [--json OUT]

``--json docs/unscattered.json`` writes the rows as the site's data file (``written_by``: the command;
``rows``: case, tally, colour, rel_rmse, flip, brightness, unlit_hue, reference_noise …), which the pages
read (through-body.md, lean.md).

A case is as in ``objects_budget.py`` (``name:mesh:mm per unit:up:material:points:photons:light:view``;
the material may hold a colon, ``homogeneous:potato``), or ``pig`` (the main job's Figure 2, its shipped
reference).  Each row prints the relative RMSE, FLIP and brightness, each region's brightness and the
unlit region's hue (each channel's share of its light over the reference's, R G B: 1 is right), and the
beams' mean unscattered fraction.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from translucency import evaluate_report, save_model
from translucency.acquire.mesh import acquire_mesh, object_volume
from translucency.fit.mesh import fit_mesh
from translucency.io.mesh import load_mesh
from translucency.io.mesh_dataset import open_mesh_dataset
from translucency.mitsuba import mesh_scene
from translucency.pipeline import FIGURE2_REFERENCE_SPP, figure2_scene
from translucency.render.camera import Camera
from translucency.render.compare import compare, region_errors
from translucency.render.lights import parse_light
from translucency.render.picture import VertexPicture, coverage
from translucency.render.reference import converged_reference
from translucency.render.tonemap import auto_exposure, save_images
from translucency.transport.matrices import transport_matrices
from translucency.transport.relight import relight_object


def scene_of(case: str, meshes: Path, size):
    """(name, points, photons, mesh, volume, light, camera, spp or None) of a case spec, ``pig`` or
    ``pig:POINTS:PHOTONS`` (the main job's pig, 96 × 8,000 unless given)."""
    if case == "pig" or case.startswith("pig:"):
        mesh, volume, light, camera = figure2_scene()
        points, photons = (int(v) for v in (case.split(":")[1:] or (96, 8000)))
        name = "pig" if case == "pig" else f"pig-{points}x{photons}"
        return name, points, photons, mesh, volume, light, camera, FIGURE2_REFERENCE_SPP
    parts = case.split(":")
    (name, file, scale, up), material = parts[:4], ":".join(parts[4:-5])
    points, photons, kind, light, view = parts[-5:]
    mesh = load_mesh(meshes / file, scale_mm=float(scale), up=up)
    volume = object_volume(material, mesh, 1.0, seed=3)
    camera = Camera.looking_at(mesh, [float(v) for v in view.split(",")], *size)
    return name, int(points), int(photons), mesh, volume, parse_light(f"{kind}:{light}"), camera, None


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument("--case", action="append", required=True, help="a case spec (module docstring) or pig")
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel of each of the two references")
    ap.add_argument("--size", type=int, nargs=2, default=(128, 96))
    ap.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="unscattered_")))
    ap.add_argument(
        "--held-out",
        action="store_true",
        help="also evaluate both colours against another acquisition (seed 4, 4x the photons, same filling)",
    )
    ap.add_argument("--json", type=Path, help="also write the rows here (the site's docs/unscattered.json)")
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
        for tally in ("counted", "apart"):
            t = time.perf_counter()
            data = acquire_mesh(
                mesh, volume, args.work / f"{name}_{P}x{N}_{tally}.zarr", n_points=P, photons=N, seed=3,
                chunk_points=32, index_matched=True, unscattered=tally,
            )  # fmt: skip
            t_acquire = time.perf_counter() - t
            ds = open_mesh_dataset(data)
            direct = np.asarray(ds.group["unscattered"][...]).mean(0) if "unscattered" in ds.group else None
            truth = None
            if args.held_out and tally == "apart":
                truth = acquire_mesh(
                    mesh, volume, args.work / f"{name}_{P}x{4 * N}_truth.zarr", n_points=P, photons=4 * N,
                    seed=4, chunk_points=32, index_matched=True,
                )  # fmt: skip
            for colour in ("shared", "per-channel"):
                model = fit_mesh(data, "iso", colour=colour).model
                if truth is not None:
                    path = args.work / f"{name}_{colour}.model.zip"
                    path.unlink(missing_ok=True)  # (this script's own file of an earlier run)
                    save_model(model, path)
                    held = evaluate_report(
                        path, data, truth=truth, report=args.work / f"{name}_{colour}_held", paper=True
                    )
                    h = held.summary
                    print(f"{name:<22} held out, {colour:<12} rel L2 {h['rel_l2']:.4f}"
                          f"  (the truth's noise {h['noise_floor']['all']:.4f})", flush=True)  # fmt: skip
                L, E, _ = relight_object(
                    transport_matrices(model, mesh, through=False), mesh, scene, light, camera.origin
                )
                ours = picture.draw(L)
                save_images(ours, args.work / f"{name}_{tally}_{colour}", exposure)
                cmp = compare(reference, ours, mask)
                regions = region_errors(mesh, scene, camera, E, reference, ours, mask)
                row = {
                    "case": name,
                    "tally": tally,
                    "colour": colour,
                    "rel_rmse": cmp["rel_rmse"],
                    "flip": cmp["flip_mean_object"],
                    "brightness": float(ours[mask].mean() / reference[mask].mean()),
                    "regions": {k: v["brightness"] for k, v in regions.items()},
                    "unlit_hue": regions["unlit"]["colour"],
                    "reference_noise": info["noise"],
                    "unscattered": None if direct is None else direct.tolist(),
                    "acquire_s": t_acquire,
                }
                out.append(row)
                by_region = " ".join(f"{k} {v:.2f}x" for k, v in row["regions"].items() if k != "all")
                print(
                    f"{name:<22} {tally:<8} {colour:<12} rel RMSE {row['rel_rmse']:.3f}  "
                    f"FLIP {row['flip']:.3f}  brightness {row['brightness']:.3f}  ({by_region})  unlit hue "
                    f"{np.round(row['unlit_hue'], 2).tolist()}  noise {info['noise']:.3f}"
                    + ("" if direct is None else f"  unscattered {np.round(direct, 4).tolist()}"),
                    flush=True,
                )
    (args.work / "unscattered.json").write_text(json.dumps(out, indent=2))
    if args.json:
        written_by = "python benchmarks/unscattered.py " + " ".join(sys.argv[1:])
        args.json.write_text(json.dumps({"written_by": written_by, "rows": out}, indent=1) + "\n")
    figure(args.work, sorted({r["case"] for r in out}, key=[r["case"] for r in out].index))
    print(f"written: {args.work / 'unscattered.json'}, {args.work / 'unscattered.png'}")
    return 0


def figure(work: Path, cases: list[str]) -> None:
    """One row per case: the reference, the paper's shared colour and a fall-off per channel (both on the
    tally with the unscattered light apart), each at the reference's exposure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    columns = (("reference", "volpath reference"), ("apart_shared", "shared colour (paper)"),
               ("apart_per-channel", "per-channel fall-off"))  # fmt: skip
    fig, axes = plt.subplots(len(cases), 3, figsize=(9, 2.4 * len(cases)), squeeze=False)
    for r, case in enumerate(cases):
        for c, (stem, title) in enumerate(columns):
            ax = axes[r, c]
            ax.imshow(Image.open(work / f"{case}_{stem}.png"))
            ax.set_xticks([]), ax.set_yticks([])
            if r == 0:
                ax.set_title(title, fontsize=10)
            if c == 0:
                ax.set_ylabel(case, fontsize=9)
    fig.tight_layout()
    fig.savefig(work / "unscattered.png", dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    raise SystemExit(main())
