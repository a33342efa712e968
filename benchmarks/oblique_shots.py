"""A model from a lab's oblique laser shots against one from ``acquire mesh --incidence`` at the same number
of shots, each drawn back-lit with the lean (``render --angles``) and without, against a converged volpath
reference.

    python benchmarks/oblique_shots.py --meshes ../shared/meshes --spp 2304 [--points 24] [--polar 60]
        [--photons 5000] [--cameras 8] [--work DIR]

The case is the back-lit marble cow of ``default_transport.py`` and ``lean_objects.py``
(``spot-marble-backlit``; its reference is cached under the same key):

1. **the virtual DISCO's way**: ``acquire mesh --incidence POLAR --azimuths 4`` at P points — the normal beam
   and four oblique ones a point, 5 P shots — fitted (the lean from the oblique beams against the normal one,
   ``fit/lean.py``);
2. **a lab's way**: 5 P shots, one a point (the 5 P farthest-point vertices), each arriving POLAR degrees off
   the normal from an azimuth where the laser's ray reaches the point unobstructed, photographed by the
   splat generator (``tests/generators/splat_rig.py``, its Lambertian law: the import's own, so that what
   differs is the lean, not the exit law) through CAMERAS cameras, imported and fitted (the lean from the
   shots' own asymmetry, ``fit/lean_shots.py``).

Both with the same photons a shot, both drawn by ``render``'s chain (``picture_check``).  Prints one line per
model and drawing, and a JSON object.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from translucency.acquire.mesh import acquire_mesh  # noqa: E402
from translucency.angles import Incidence  # noqa: E402
from translucency.geometry import farthest_points  # noqa: E402
from translucency.mitsuba import mesh_scene, rays  # noqa: E402
from translucency.pipeline.picture_check import picture_check  # noqa: E402
from translucency.rig.object.importer import import_object  # noqa: E402
from unscattered import scene_of  # noqa: E402

CASE = "spot-marble-backlit:spot.obj:20:y:marble:128:2000:directional:0.8,-1.6,0.2,1:1,-1.6,0.7"


def oblique_beams(mesh, incident, polar_deg: float, seed: int = 0) -> tuple[np.ndarray, int]:
    """Each shot's direction of flight (P, 3): ``polar_deg`` off the inward normal, from the first of 12
    azimuths (random start) whose ray from 40 mm out reaches the vertex unobstructed — else along the
    normal; and how many are oblique."""
    from generators.splat_rig import aim_point

    scene = mesh_scene(mesh)
    rng = np.random.default_rng(seed)
    N = np.asarray(mesh.vertex_normals, np.float64)
    out, n_oblique = np.zeros((len(incident), 3)), 0
    ring = [f[f >= 0] for f in mesh.vertex_faces]  # the faces around each vertex
    for j, v in enumerate(incident):
        n = N[v]
        t = np.cross(n, [0.0, 0.0, 1.0] if abs(n[2]) < 0.9 else [1.0, 0.0, 0.0])
        t /= np.linalg.norm(t)
        b = np.cross(n, t)
        out[j] = -n
        start = rng.uniform(0, 2 * np.pi)
        for phi in start + np.arange(12) * np.pi / 6:
            toward = np.cos(np.radians(polar_deg)) * n + np.sin(np.radians(polar_deg)) * (
                np.cos(phi) * t + np.sin(phi) * b
            )
            # as the import casts it: from 40 mm out, the first surface met must be the vertex's, facing it
            aim = aim_point(mesh, int(v), -toward)
            hit = scene.ray_intersect(rays((aim + 40.0 * toward)[None], -toward[None]))
            t, face = float(np.asarray(hit.t)[0]), int(np.asarray(hit.prim_index)[0])
            if (
                bool(np.asarray(hit.is_valid())[0])
                and abs(t - 40.0) < 0.05
                and mesh.face_normals[face] @ toward > 0.05
                and (mesh.face_normals[ring[v]] @ toward > 0.05).all()  # a ray at a vertex may meet any
            ):
                out[j], n_oblique = -toward, n_oblique + 1
                break
    return out, n_oblique


def main() -> int:
    from generators.splat_rig import cameras_on_sphere, splat_rig

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument(
        "--spp", type=int, default=2304, help="samples per pixel of each of the reference's renders"
    )
    ap.add_argument("--points", type=int, default=24, help="points of the --incidence acquisition (5x shots)")
    ap.add_argument("--polar", type=float, default=60.0, help="degrees off the normal of the oblique beams")
    ap.add_argument("--photons", type=int, default=5000, help="photons a shot, both ways")
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--resolution", type=int, nargs=2, default=(96, 72))
    ap.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="oblique_shots_")))
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    name, _, _, mesh, volume, light, camera, _ = scene_of(CASE, args.meshes, (128, 96))
    P, shots = args.points, 5 * args.points

    t = time.perf_counter()
    disco = args.work / f"incidence_{P}x5.zarr"
    if not disco.is_dir():
        acquire_mesh(
            mesh, volume, disco, n_points=P, photons=args.photons, seed=3, chunk_points=32,
            index_matched=True, reentry=True, incidence=Incidence((args.polar,), 4),
        )  # fmt: skip
    print(f"--incidence: {P} points x 5 beams in {time.perf_counter() - t:.0f} s", file=sys.stderr)

    t = time.perf_counter()
    incident = farthest_points(np.asarray(mesh.vertices), shots)
    incoming, n_oblique = oblique_beams(mesh, incident, args.polar)
    rig = args.work / "lab_shots"
    if not (rig / "object.json").is_file():
        W, H = args.resolution
        cams = cameras_on_sphere(mesh, args.cameras, W, H, seed=0)
        splat_rig(mesh, volume, rig, incident=incident, cameras=cams, photons=args.photons, seed=7,
                  incoming=incoming)  # fmt: skip
    lab = args.work / "lab_shots.zarr"
    if not lab.is_dir():
        import_object(rig, lab)
    print(
        f"a lab's shots: {shots} ({n_oblique} at {args.polar:g} deg, the rest blocked: normal), photographed "
        f"and imported in {time.perf_counter() - t:.0f} s",
        file=sys.stderr,
    )
    out = {"case": name, "shots": shots, "oblique": n_oblique, "photons": args.photons}
    for angles in (True, False):
        res = picture_check(
            mesh, volume, {"incidence": disco, "shots": lab}, light, camera, reference_spp=args.spp,
            angles=angles, out=args.work / ("angles" if angles else "paper"),
        )  # fmt: skip
        tag = "with the lean (--angles)" if angles else "without"
        for k in ("incidence", "shots"):
            r = res[k]
            print(f"{k:<10} {tag:<26} vs volpath {r['vs_volpath']:.3f} (brightness "
                  f"{r['brightness_vs_volpath']:.3f})", flush=True)  # fmt: skip
        noise = res["reference_noise"]
        print(f"  shots vs incidence {res['shots']['vs_first']:.3f}; reference noise {noise:.3f}")
        out["angles" if angles else "paper"] = res
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
