"""The photon tally drawn pixel by pixel, against the volpath reference: do our two truths agree on light
that crosses the body?

Every model is fitted to the photon tally (``acquire mesh``: ``mesh_random_walk``), every picture is
judged against Mitsuba's volpath.  If the two disagreed where light crosses the body, the error budget's
floor would hold that disagreement and no transport could go below it.  This script takes the tally out of
the per-vertex pipeline entirely: light tracing from the light, through the walk, to the camera's pixels.

    python benchmarks/tally_picture.py --meshes ../shared/meshes --spp 2304 --case CASE [--case CASE ...]

A case is as in ``objects_budget.py`` (``name:mesh:mm per unit:up:material:points:photons:light:view``;
the points and photons are not used).  For each channel, ``--starts`` points are drawn uniformly over
the surface; each is lit by the light's shadowed irradiance E(x) (a delta light's, W/mm²) and sends
``--photons`` walks in along the light's direction (index-matched, re-entry: ``acquire mesh``'s physics).
An exit x_o leaving along ω_o within ``--cone`` degrees of the direction to the eye, and seen from it
(one shadow ray), adds to its pixel

    L_pixel += w / (π sin²c · Ω_pixel · |eye − x_o|²),     w = A E(x) / (S k),

the radiance of the exits through the pixel's footprint A_foot = Ω_pixel |eye − x_o|² / cos θ_o into a
cone of projected solid angle π sin²c cos θ_o (A the surface's area, S starts, k walks each).  Unscattered
exits are a delta along the beam, which no pinhole sees: left out, as the renderer leaves them.  The
tally's own noise comes from two halves of different seeds.  Rows: relative RMSE, brightness and each
region's brightness (``render.compare.region_errors``) at full resolution and in 4 × 4 blocks, beside the
reference's own noise.  The cone and the pixel footprint blur the tally a little; the blocks show what
is left once that blur is below the block.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from translucency.acquire.mesh import object_volume
from translucency.acquire.mesh_walk import EXIT, mesh_random_walk
from translucency.io.mesh import load_mesh
from translucency.mitsuba import load_plugin, mesh_scene, mitsuba, rays
from translucency.mitsuba.sensors import pinhole_sensor_dict
from translucency.render.camera import Camera
from translucency.render.compare import compare, region_errors
from translucency.render.lights import parse_light
from translucency.render.picture import coverage
from translucency.render.reference import converged_reference
from translucency.render.tonemap import auto_exposure, save_images
from translucency.transport.irradiance import vertex_irradiance


def case_scene(case: str, meshes: Path, size):
    """(name, mesh, volume, light, camera) of a case spec (module docstring)."""
    parts = case.split(":")
    (name, file, scale, up), material = parts[:4], ":".join(parts[4:-5])
    kind, light, view = parts[-3:]
    mesh = load_mesh(meshes / file, scale_mm=float(scale), up=up)
    volume = object_volume(material, mesh, 1.0, seed=3)
    camera = Camera.looking_at(mesh, [float(v) for v in view.split(",")], *size)
    return name, mesh, volume, parse_light(f"{kind}:{light}"), camera


def surface_starts(mesh, n: int, rng) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, n, face): ``n`` points uniform over the surface's area, with their faces' outward normals."""
    area = np.asarray(mesh.area_faces, dtype=np.float64)
    face = rng.choice(len(area), size=n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    tri = np.asarray(mesh.triangles, dtype=np.float64)[face]
    x = tri[:, 0] + u[:, None] * (tri[:, 1] - tri[:, 0]) + v[:, None] * (tri[:, 2] - tri[:, 0])
    return x, np.asarray(mesh.face_normals, dtype=np.float64)[face], face


class PixelSplat:
    """Where an exit lands on the camera's film and how much radiance one unit of power adds there."""

    def __init__(self, scene, camera: Camera, cone_deg: float):
        mi = mitsuba()
        self.mi, self.scene, self.camera = mi, scene, camera
        self.sensor = load_plugin(pinhole_sensor_dict(camera, 1))
        self.eye = np.asarray(camera.origin, dtype=np.float64)
        self.cos_c = float(np.cos(np.radians(cone_deg)))
        self.projected_cone = np.pi * (1.0 - self.cos_c**2)  # π sin²c
        # a pixel's solid angle: (the film plane's pixel pitch at unit distance)² cos³ of its angle off
        # the axis (Mitsuba's perspective camera, fov along x)
        self.pitch = 2.0 * np.tan(np.radians(camera.fov) / 2.0) / camera.width
        axis = np.asarray(camera.target, dtype=np.float64) - self.eye
        self.axis = axis / np.linalg.norm(axis)

    def add(self, image, pos, direction, face_n, weight) -> None:
        """Splat exits (positions, unit exit directions, their faces' normals, power each) into ``image``."""
        mi = self.mi
        to_eye = self.eye - pos
        dist = np.linalg.norm(to_eye, axis=1)
        to_eye /= dist[:, None]
        keep = (np.einsum("ij,ij->i", direction, to_eye) > self.cos_c) & (
            np.einsum("ij,ij->i", face_n, to_eye) > 0
        )
        pos, to_eye, dist, weight = pos[keep], to_eye[keep], dist[keep], weight[keep]
        if not len(pos):
            return
        # seen from the eye: nothing between the exit and the camera
        o = pos + face_n[keep] * 1e-3
        blocked = np.asarray(self.scene.ray_test(rays(o, to_eye, dist - 2e-3)))
        pos, to_eye, dist, weight = pos[~blocked], to_eye[~blocked], dist[~blocked], weight[~blocked]
        it = mi.Interaction3f()
        it.p = mi.Point3f(*[mi.Float(np.ascontiguousarray(pos[:, k], dtype=np.float32)) for k in range(3)])
        ds, w = self.sensor.sample_direction(it, mi.Point2f(0.5, 0.5))
        uv = np.stack([np.asarray(ds.uv.x), np.asarray(ds.uv.y)], axis=1)
        inside = np.asarray(w[0]) > 0
        px = np.floor(uv[inside]).astype(int)
        H, W = image.shape
        ok = (px[:, 0] >= 0) & (px[:, 0] < W) & (px[:, 1] >= 0) & (px[:, 1] < H)
        px = px[ok]
        cos_a = np.einsum("ij,j->i", -to_eye[inside][ok], self.axis)
        omega_pixel = self.pitch**2 * cos_a**3
        L = weight[inside][ok] / (self.projected_cone * omega_pixel * dist[inside][ok] ** 2)
        np.add.at(image, (px[:, 1], px[:, 0]), L)


def tally_image(mesh, volume, light, camera, starts, photons, cone_deg, seed, chunk=4096):
    """(H, W, 3) the light-traced picture of the tally (module docstring), one seed."""
    scene = mesh_scene(mesh)
    splat = PixelSplat(scene, camera, cone_deg)
    image = np.zeros((camera.height, camera.width, 3))
    rng = np.random.default_rng(seed)
    x, n, _ = surface_starts(mesh, starts, rng)
    extent = float(np.linalg.norm(mesh.extents))
    E = np.asarray(light.irradiance_at(scene, x, n, extent), dtype=np.float64)  # (S,) W/mm², shadowed
    w_dir, _, _ = light.arrival(scene, x, n)
    lit = E > 0
    x, n, E, incoming = x[lit], n[lit], E[lit], -np.asarray(w_dir, dtype=np.float64)[lit]
    A = float(mesh.area)
    face_normals = np.asarray(mesh.face_normals, dtype=np.float64)
    for ch in range(3):
        for lo in range(0, len(x), chunk):
            hi = min(lo + chunk, len(x))
            res = mesh_random_walk(
                scene, mesh.bounds, volume, ch, x[lo:hi], n[lo:hi], photons, seed=seed + 7919 * ch,
                first_point=lo, index_matched=True, reentry=True, incoming=incoming[lo:hi],
            )  # fmt: skip
            out = (res.code == EXIT) & (res.scatters > 0)
            src = np.repeat(np.arange(lo, hi), photons)[out]
            d = res.direction[out].astype(np.float64)
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            power = A * E[src] / (starts * photons)
            x_o = res.position[out].astype(np.float64)
            splat.add(image[..., ch], x_o, d, face_normals[res.face[out]], power)
    return image


def blocks(img, mask, b=4):
    """Block means of an (H, W, 3) picture over the object's pixels, and which blocks hold any."""
    H, W = mask.shape
    h, w = H // b, W // b
    m = mask[: h * b, : w * b].reshape(h, b, w, b).astype(float)
    s = (img[: h * b, : w * b] * mask[: h * b, : w * b, None]).reshape(h, b, w, b, 3).sum(axis=(1, 3))
    cnt = m.sum(axis=(1, 3))
    return s / np.maximum(cnt, 1)[..., None], cnt >= b * b / 2


def rel_rmse(ref, ours, mask):
    return float(np.sqrt(np.mean((ours[mask] - ref[mask]) ** 2)) / np.sqrt(np.mean(ref[mask] ** 2)))


def spread(diff, ref, mask):
    """The RMS of ``diff`` over the mask relative to the reference's: a noise on the scale of rel_rmse."""
    return float(np.sqrt(np.mean(diff[mask] ** 2)) / np.sqrt(np.mean(ref[mask] ** 2)))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument("--case", action="append", required=True)
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel of each of the two references")
    ap.add_argument("--size", type=int, nargs=2, default=(128, 96))
    ap.add_argument("--starts", type=int, default=100_000, help="surface points per half and channel")
    ap.add_argument("--photons", type=int, default=20, help="walks per surface point")
    ap.add_argument("--cone", type=float, default=15.0, help="degrees about the direction to the eye")
    ap.add_argument("--work", type=Path, default=Path(tempfile.mkdtemp(prefix="tally_picture_")))
    args = ap.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    rows = []
    for case in args.case:
        name, mesh, volume, light, camera = case_scene(case, args.meshes, args.size)
        mask = coverage(mesh, camera)
        reference, info = converged_reference(mesh, volume, light, camera, mask, spp=args.spp)
        t = time.perf_counter()
        halves = [
            tally_image(mesh, volume, light, camera, args.starts, args.photons, args.cone, seed)
            for seed in (11, 12)
        ]
        seconds = time.perf_counter() - t
        tally = 0.5 * (halves[0] + halves[1])
        exposure = auto_exposure(reference, mask)
        save_images(tally, args.work / f"{name}_tally", exposure)
        save_images(reference, args.work / f"{name}_reference", exposure)
        cmp = compare(reference, tally, mask)
        # the tally's own noise: the halves' difference / 2 is the mean's error, relative to the reference
        noise = spread(0.5 * (halves[0] - halves[1]), reference, mask)
        np.savez_compressed(args.work / f"{name}_tally_halves.npz", a=halves[0], b=halves[1])
        E = vertex_irradiance(mesh, mesh_scene(mesh), light)
        regions = region_errors(mesh, mesh_scene(mesh), camera, E, reference, tally, mask)
        rb, keep = blocks(reference, mask)
        tb, _ = blocks(tally, mask)
        hb = [blocks(h, mask)[0] for h in halves]
        row = {
            "case": name,
            "rel_rmse": cmp["rel_rmse"],
            "flip": cmp["flip_mean_object"],
            "brightness": float(tally[mask].mean() / reference[mask].mean()),
            "channel_brightness": (tally[mask].mean(0) / reference[mask].mean(0)).tolist(),
            "tally_noise": noise,
            "reference_noise": info["noise"],
            "blocks_rel_rmse": rel_rmse(rb, tb, keep),
            "blocks_tally_noise": spread(0.5 * (hb[0] - hb[1]), rb, keep),
            "regions": {k: v["brightness"] for k, v in regions.items() if k != "all"},
            "unlit_hue": regions["unlit"]["colour"],
            "seconds": seconds,
        }
        rows.append(row)
        print(
            f"{name:<22} tally vs volpath: rel RMSE {row['rel_rmse']:.3f}  FLIP {row['flip']:.3f}  "
            f"brightness {row['brightness']:.3f} (R G B {np.round(row['channel_brightness'], 3).tolist()})  "
            f"noise: tally {noise:.3f}, reference {info['noise']:.3f};  in 4x4 blocks rel RMSE "
            f"{row['blocks_rel_rmse']:.3f} (tally noise {row['blocks_tally_noise']:.3f});  "
            + " ".join(f"{k} {v:.2f}x" for k, v in row["regions"].items())
            + f"  unlit hue {np.round(row['unlit_hue'], 2).tolist()}  {seconds:.0f} s",
            flush=True,
        )
    (args.work / "tally_picture.json").write_text(json.dumps(rows, indent=2))
    print(f"written: {args.work / 'tally_picture.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
