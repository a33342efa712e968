"""The lean against the paper's model, as ``render`` draws them, on an object case with a converged reference
(issue 37, item 3).

For a case of ``objects_table.py``'s form, one acquisition with the normal beam and ``--polar`` × 4 oblique
beams per incident point (``acquire mesh --incidence``), one fit (the paper's model, with the lean fitted
from the oblique beams: model/lean.py), then the object drawn

* with the paper's model (``render``),
* with the lean of the light (``render --angles``),
* with the lean both ways (the light's and the camera's: ``leaned(..., exit=True)``),

each against the converged volpath reference (relative RMSE, FLIP, brightness).  **Held out**: a second
acquisition with another seed (other incident points, other photons) predicts nothing of the fit; its
oblique beams are predicted from its own normal beam with the fitted κ (blended to its points) and
without (the paper's model: the normal beam's shape, scaled to the oblique total), and the relative L2
error of each over the power per vertex is printed; and, as ``evaluate --truth`` reports it
(evaluate/oblique_errors.py), the fitted model's oblique beams against the held-out ones.  Also the
relight time per light of both.

    python benchmarks/lean_objects.py --meshes ../shared/meshes --spp 2304 \\
        --case spot-marble-backlit:spot.obj:20:y:marble:128:2000:directional:0.8,-1.6,0.2,1:1,-1.6,0.7

``--case pig``: the main job's pig (Figure 2: 96 points × 8,000 photons, its light, camera and the shipped
reference).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from translucency.acquire.mesh import acquire_mesh, object_volume
from translucency.angles import Incidence
from translucency.evaluate.oblique_errors import oblique_errors
from translucency.fit.mesh import fit_mesh
from translucency.io.mesh import load_mesh
from translucency.io.mesh_dataset import open_mesh_dataset
from translucency.mitsuba import mesh_scene
from translucency.model.lean import lean_vector
from translucency.pipeline import FIGURE2_REFERENCE_SPP, figure2_scene
from translucency.render.camera import Camera
from translucency.render.compare import compare, region_errors
from translucency.render.lights import parse_light
from translucency.render.picture import VertexPicture, coverage
from translucency.render.reference import converged_reference
from translucency.render.tonemap import auto_exposure, save_images
from translucency.transport.irradiance import vertex_irradiance
from translucency.transport.lean import lean_pairs, leaned
from translucency.transport.matrices import transport_matrices
from translucency.transport.parameters import neighbour_weights
from translucency.transport.relight import exit_fresnel, relight_vertices, view_cosines

CASE = "spot-marble-backlit:spot.obj:20:y:marble:128:2000:directional:0.8,-1.6,0.2,1:1,-1.6,0.7"


def held_out_errors(ds, lean_v) -> dict:
    """Relative L2 errors (over the power per vertex, all points, beams and channels) of the held-out
    data set's oblique beams predicted from its normal beam with and without the lean (κ, λ per vertex,
    (V, 2, 3))."""
    vertices = np.asarray(ds["vertices"], dtype=np.float64)
    area = np.asarray(ds["vertex_area"], dtype=np.float64)
    incident = np.asarray(ds["incident"])
    frames = ds.incident_frames()
    w = ds.incidence.world(frames)[:, 1:]
    R0_all, R1_all = np.asarray(ds["R_d"], np.float64), np.asarray(ds["R_d_oblique"], np.float64)
    err = {"paper": 0.0, "lean": 0.0, "norm": 0.0}
    for p, j in enumerate(incident):
        d = vertices - vertices[j]
        r = np.linalg.norm(d, axis=1)
        use = r > 0
        d_hat = np.divide(d, r[:, None], out=np.zeros_like(d), where=use[:, None])
        ell = lean_vector(w[p], frames[p, 2][None])  # (D, 3)
        a, depth = ell @ d_hat.T, (ell @ frames[p, 2])[:, None] * r[None, :]  # (D, V) each
        M0 = area[:, None] * R0_all[p] * use[:, None]  # (V, 3)
        M1 = area[None, :, None] * R1_all[p] * use[None, :, None]  # (D, V, 3)
        s = M1.sum(1) / M0.sum(0)  # (D, 3)
        for name, (k, lam) in (("paper", np.zeros((2, 3))), ("lean", lean_v[j])):
            shaped = M0[None] * np.exp(a[..., None] * k - depth[..., None] * lam)
            pred = s[:, None, :] * shaped / shaped.sum(1, keepdims=True) * M0.sum(0)[None, None, :]
            err[name] += float(np.sum((pred - M1) ** 2))
        err["norm"] += float(np.sum(M1**2))
    return {k: float(np.sqrt(err[k] / err["norm"])) for k in ("paper", "lean")}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument("--case", default=CASE)
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel of each of the two references")
    ap.add_argument("--size", type=int, nargs=2, default=(128, 96))
    ap.add_argument("--polar", type=float, default=60.0, help="the oblique beams' polar angle, degrees")
    ap.add_argument("--colour", default="shared", help="the fit's colour: shared (the paper's), per-channel")
    ap.add_argument("--incidence", default="half-space", help="the incidence law (render --incidence-law)")
    ap.add_argument("--through", action="store_true", help="with the through-body table (render --through)")
    ap.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="lean_objects_")))
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    if args.case == "pig":  # the main job's Figure 2: its object, light, camera and shipped reference
        name, P, N = "pig", 96, 8000
        mesh, volume, light, camera = figure2_scene()
        args.spp = FIGURE2_REFERENCE_SPP
    else:
        parts = args.case.split(":")  # the material may hold a colon itself (homogeneous:potato)
        (name, file, scale, up), material = parts[:4], ":".join(parts[4:-5])
        points, photons, kind, light_text, view = parts[-5:]
        P, N = int(points), int(photons)
        mesh = load_mesh(args.meshes / file, scale_mm=float(scale), up=up)
        volume = object_volume(material, mesh, 1.0, seed=3)
        light = parse_light(f"{kind}:{light_text}")
        camera = Camera.looking_at(mesh, [float(v) for v in view.split(",")], *args.size)
    mask = coverage(mesh, camera)
    reference, info = converged_reference(mesh, volume, light, camera, mask, spp=args.spp)
    exposure = auto_exposure(reference, mask)
    save_images(reference, args.work / "reference", exposure)

    def acquire(seed):
        t = time.perf_counter()
        path = acquire_mesh(
            mesh, volume, args.work / f"{name}_{P}x{N}_{seed}_lean{args.polar:g}.zarr", n_points=P,
            photons=N, seed=seed, chunk_points=32, index_matched=True, reentry=True,
            incidence=Incidence((args.polar,), 4),
        )  # fmt: skip
        return path, time.perf_counter() - t

    data, t_acquire = acquire(3)
    fit = fit_mesh(data, "iso", colour=args.colour)
    model = fit.model
    lean = model.measured["lean"]  # (P, 2, 3): κ, λ
    print(
        f"acquired in {t_acquire:.1f} s; over the points (R, G, B medians) "
        f"κ {np.median(lean[:, 0], 0).round(2)}, λ {np.median(lean[:, 1], 0).round(3)} mm⁻¹"
    )
    scene = mesh_scene(mesh)
    picture = VertexPicture(mesh, camera, spp=16, light=light)
    T = transport_matrices(model, mesh, through=args.through)
    if args.through and not T.through:
        print("the model has no through-body table: drawn without it")
    law = T.incidence(args.incidence)
    E = vertex_irradiance(mesh, scene, light, incidence=law)
    exit_law = law.exit(view_cosines(mesh, camera.origin))
    fresnel = exit_fresnel(mesh, camera.origin, 1.0)[:, None]
    rows = []
    pairs = lean_pairs(T, mesh, exit=True)  # (the exit normalisation too: the both-ways row)
    for label, transport in (
        ("paper's model", T),
        ("lean of the light (render --angles)", leaned(T, mesh, scene, light, camera.origin, pairs=pairs)),
        ("lean both ways", leaned(T, mesh, scene, light, camera.origin, exit=True, pairs=pairs)),
    ):
        L = relight_vertices(transport, E) * fresnel
        img = picture.draw(L if exit_law is None else L * exit_law)
        cmp = compare(reference, img, mask)
        stem = "".join(c if c.isalnum() else "_" for c in label) + ("" if args.colour == "shared" else "_pc")
        stem += "" if args.incidence == "half-space" else "_" + args.incidence.replace("-", "_")
        stem += "_through" if args.through else ""
        save_images(img, args.work / stem, exposure)
        regions = region_errors(mesh, scene, camera, E, reference, img, mask)
        rows.append(
            {
                "row": label,
                "rel_rmse": cmp["rel_rmse"],
                "flip": cmp["flip_mean_object"],
                "brightness": float(img[mask].mean() / reference[mask].mean()),
                "regions": {k: v["rel_rmse"] for k, v in regions.items()},
                "region_brightness": {k: v["brightness"] for k, v in regions.items()},
            }
        )
        by_region = " ".join(f"{k} {v['brightness']:.2f}x" for k, v in regions.items())
        print(f"{label:<34} rel RMSE {cmp['rel_rmse']:.3f}  FLIP {cmp['flip_mean_object']:.3f}  "
              f"brightness {rows[-1]['brightness']:.3f}  ({by_region})", flush=True)  # fmt: skip
    # relight per light: the paper's one product against the lean's pairs, then its products
    timing = {}
    for label, run in (
        ("paper", lambda: relight_vertices(T, E)),
        ("lean", lambda: relight_vertices(leaned(T, mesh, scene, light, camera.origin, pairs=pairs), E)),
    ):
        run()
        t = time.perf_counter()
        for _ in range(3):
            run()
        timing[label] = (time.perf_counter() - t) / 3
    print(f"relight per light: paper {timing['paper'] * 1e3:.1f} ms, lean {timing['lean'] * 1e3:.1f} ms "
          f"({timing['lean'] / timing['paper']:.1f}x); {T.nnz:,} near pairs")  # fmt: skip
    # held out: another seed's points and photons
    other, _ = acquire(4)
    w, idx = neighbour_weights(model, mesh)
    lean_v = np.einsum("vk,vkac->vac", w, lean[idx])
    held = held_out_errors(open_mesh_dataset(other), lean_v)
    print(f"held out (seed 4), oblique beams from the normal one: paper {held['paper']:.3f}, "
          f"lean {held['lean']:.3f} (rel. L2 of the power per vertex)")  # fmt: skip
    # as `evaluate --truth` reports it: the fitted model's profile, the model's own incidence law
    evaluated = oblique_errors(model, other)
    print(f"evaluate --truth (seed 4), oblique beams from the fitted model: paper {evaluated['paper']:.3f}, "
          f"lean {evaluated['lean']:.3f}, the truth's noise {evaluated['noise']:.3f}")  # fmt: skip
    out = {
        "case": args.case,
        "reference_noise": info["noise"],
        "kappa_median": np.median(lean[:, 0], 0).tolist(),
        "lambda_median": np.median(lean[:, 1], 0).tolist(),
        "rows": rows,
        "relight_s": timing,
        "held_out": held,
        "evaluate_truth": evaluated,
        "acquire_s": t_acquire,
    }
    out["colour"], out["incidence"], out["through"] = args.colour, args.incidence, bool(T.through)
    tag = (
        ("" if args.colour == "shared" else "_" + args.colour)
        + ("" if args.incidence == "half-space" else "_" + args.incidence)
        + ("_through" if args.through else "")
    )
    (args.work / f"lean_objects{tag}.json").write_text(json.dumps(out, indent=2))
    print(f"reference noise {info['noise']:.3f}; written: {args.work / f'lean_objects{tag}.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
