"""The virtual rig's photographs against the photon tally, camera by camera, before any import.

The import of the virtual rig's photographs (``object_import_energy.py --generators=rig``) reads the flank
of ``spot.obj`` 1.6–1.7× the tally at 4–8 mm.  Either the photographs (Mitsuba ``volpath`` with the rig's
0.3 mm disc laser) and the tally (``mesh_random_walk``, a pencil) disagree, or the import reads them
wrongly.  This script takes the import out: for one shot it renders each camera's photograph with
``volpath`` (:func:`translucency.rig.object.photographs.render_shot`, two seeds) and light-traces the
tally's own walks from the same vertex into the same camera's pixels, each exit that leaves within
``--cone`` degrees of the direction to the eye and is seen from it adding

    L_pixel += w / (π sin²c · Ω_pixel · |eye − x_o|²),      w = 1 / (walks) W per W of laser power,

Ω_pixel the pixel's solid angle (cos³ of its angle off the axis over f_x f_y).  Both pictures are radiance
per W of laser power.  Each camera's pixels are banded by the distance of the surface point they see from
the hit (0–1–2–4–8–16 mm and beyond); per band and channel the script prints the photographs' sum over the
tally's, and the spread of the photographs' two seeds and of the tally's two halves (the noise of the
ratio).

    python benchmarks/rig_vs_tally.py [MESH.obj] --shot 0 [--spp 256] [--walks 2000000] [--cone 20]

MESH, size, material, cameras and shots as ``object_import_energy.py``'s defaults for ``spot.obj``
(30 mm, ``homogeneous:skin1`` on 0.5 mm voxels, 8 cameras of 96 × 72, the first three farthest-point
vertices; shot 0 is the flank's).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from object_import_energy import BANDS, object_mesh  # the same bands of distance from the hit, mm
from translucency.acquire.mesh import object_volume
from translucency.acquire.mesh_walk import EXIT, mesh_random_walk
from translucency.geometry import farthest_points
from translucency.mitsuba import mesh_scene, rays
from translucency.rig.object.photographs import LaserBeam, cameras_around, render_shot
from translucency.rig.object.surface_map import surface_map


def tally_pictures(scene, mesh, volume, cams, x_i, n_i, walks, cone_deg, seed, chunk=250_000):
    """(halves, cameras, H, W, 3): the tally's walks from ``x_i`` along −``n_i`` splatted into each camera,
    two halves of independent seeds, each scaled to the whole's power."""
    cos_c = np.cos(np.radians(cone_deg))
    cone = np.pi * (1.0 - cos_c**2)  # π sin² c
    faces_n = np.asarray(mesh.face_normals, np.float64)
    out = np.zeros((2, len(cams), cams[0].height, cams[0].width, 3))
    eyes = [(-c.R.T @ c.t).astype(np.float64) for c in cams]
    axes = [c.R[2].astype(np.float64) for c in cams]  # the optical axis in the object's frame
    per_half = walks // 2
    for half in range(2):
        for ch in range(3):
            for lo in range(0, per_half, chunk):
                k = min(chunk, per_half - lo)
                res = mesh_random_walk(
                    scene, mesh.bounds, volume, ch, x_i[None], n_i[None], k,
                    seed=seed + 1000 * half + 7919 * ch, first_point=lo // chunk,
                    index_matched=True, reentry=True,
                )  # fmt: skip
                ok = (res.code == EXIT) & (res.scatters > 0)
                x_o = res.position[ok].astype(np.float64)
                d = res.direction[ok].astype(np.float64)
                d /= np.linalg.norm(d, axis=1, keepdims=True)
                fn = faces_n[res.face[ok]]
                w = 2.0 / walks  # W per W, each half standing for the whole
                for c, (cam, eye, axis) in enumerate(zip(cams, eyes, axes)):
                    to_eye = eye - x_o
                    dist = np.linalg.norm(to_eye, axis=1)
                    to_eye /= dist[:, None]
                    toward = np.einsum("ij,ij->i", d, to_eye) > cos_c
                    keep = toward & (np.einsum("ij,ij->i", fn, to_eye) > 0)
                    if not keep.any():
                        continue
                    p, te, dd = x_o[keep], to_eye[keep], dist[keep]
                    blocked = np.asarray(scene.ray_test(rays(p + fn[keep] * 1e-3, te, dd - 2e-3)))
                    p, te, dd = p[~blocked], te[~blocked], dd[~blocked]
                    uv = cam.project(p)
                    px = np.floor(uv + 0.5).astype(int)
                    inside = np.all((px >= 0) & (px < [cam.width, cam.height]), axis=1)
                    cos_a = np.einsum("ij,j->i", -te, axis)[inside]
                    omega = cos_a**3 / (cam.K[0, 0] * cam.K[1, 1])
                    L = w / (cone * omega * dd[inside] ** 2)
                    np.add.at(out[half, c, ..., ch], (px[inside, 1], px[inside, 0]), L)
    return out


def band_sums(img, band_of_pixel):
    """(bands, 3): each band's sum of the picture (H, W, 3) over its pixels."""
    flat = img.reshape(-1, 3)
    return np.stack([flat[band_of_pixel == b].sum(0) for b in range(len(BANDS) - 1)])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh", type=Path, nargs="?", default=None)
    ap.add_argument("--size", type=float, default=30.0)
    ap.add_argument("--material", default="homogeneous:skin1")
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--resolution", default="96x72")
    ap.add_argument("--points", type=int, default=3)
    ap.add_argument("--shot", type=int, default=0)
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel of each of the two photographs")
    ap.add_argument("--walks", type=int, default=2_000_000, help="the tally's walks a channel")
    ap.add_argument("--cone", type=float, default=20.0)
    ap.add_argument("--out", type=Path, default=Path("rig_vs_tally.json"))
    args = ap.parse_args()
    W, H = (int(v) for v in args.resolution.split("x"))
    mesh = object_mesh(args.mesh, args.size)
    volume = object_volume(args.material, mesh, 0.5, seed=1)
    incident = farthest_points(np.asarray(mesh.vertices), args.points)
    v = int(incident[args.shot])
    x_i = np.asarray(mesh.vertices, np.float64)[v]
    n_i = np.asarray(mesh.vertex_normals, np.float64)[v]
    cams = cameras_around(mesh, args.cameras, W, H, seed=0)
    scene = mesh_scene(mesh)
    t = time.perf_counter()
    beam = LaserBeam()

    def shot(cam, s):
        return render_shot(mesh, volume, cam, x_i, n_i, beam, spp=args.spp, seed=s, scene=scene)

    rig = np.stack([np.stack([shot(c, s) for c in cams]) for s in (0, 1)])
    t_rig = time.perf_counter() - t
    t = time.perf_counter()
    tally = tally_pictures(scene, mesh, volume, cams, x_i, n_i, args.walks, args.cone, seed=4242)
    t_tally = time.perf_counter() - t
    print(f"shot {args.shot} (vertex {v}): volpath {t_rig:.0f} s, tally {t_tally:.0f} s")
    rows = []
    for c, cam in enumerate(cams):
        m = surface_map(mesh, cam, scene=scene)
        r = np.linalg.norm(m.position - x_i, axis=1)  # NaN where the ray misses
        band = np.searchsorted(BANDS, np.nan_to_num(r, nan=-1.0), side="right") - 1  # -1: no surface
        rig_c = [band_sums(rig[s, c], band).tolist() for s in (0, 1)]
        tally_c = [band_sums(tally[h, c], band).tolist() for h in (0, 1)]
        rows.append({"camera": c, "rig": rig_c, "tally": tally_c})
    A = np.array([r["rig"] for r in rows])  # (cameras, 2 seeds, bands, 3)
    T = np.array([r["tally"] for r in rows])  # (cameras, 2 halves, bands, 3)
    a, t = A.mean(1).sum(0), T.mean(1).sum(0)
    ratio = a / np.maximum(t, 1e-30)
    # the ratio's relative noise: two independent estimates differ by d, their mean's σ is |d| / 2;
    # the cameras' noises add in quadrature
    noise = np.hypot(
        np.sqrt(((A[:, 0] - A[:, 1]) ** 2).sum(0)) / 2 / np.maximum(a, 1e-30),
        np.sqrt(((T[:, 0] - T[:, 1]) ** 2).sum(0)) / 2 / np.maximum(t, 1e-30),
    )
    print("band (mm)    photographs / tally, R G B      (noise)")
    for b in range(len(BANDS) - 1):
        print(
            f"{BANDS[b]:>4g}-{BANDS[b + 1]:<4g}  {ratio[b, 0]:.3f} {ratio[b, 1]:.3f} {ratio[b, 2]:.3f}   "
            f"({noise[b, 0]:.3f} {noise[b, 1]:.3f} {noise[b, 2]:.3f})"
        )
    per_camera = [
        (np.asarray(r["rig"]).mean(0) / np.maximum(np.asarray(r["tally"]).mean(0), 1e-30)).round(3).tolist()
        for r in rows
    ]
    args.out.write_text(
        json.dumps(
            {
                "shot": args.shot, "vertex": v, "bands_mm": BANDS.tolist(), "ratio": ratio.round(4).tolist(),
                "noise": noise.round(4).tolist(), "per_camera_ratio": per_camera, "cameras": rows,
                "seconds": {"volpath": t_rig, "tally": t_tally},
            },
            indent=1,
        )
    )  # fmt: skip
    print(f"written: {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
