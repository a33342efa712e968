"""How fast a fitted object in a scene re-renders after its one-off preparation — a new camera (the
picture only) and a new light (the passes and the picture), at 320 x 240 and 16 samples a pixel — and how
much faster than volpath at equal error, in one run:

    python benchmarks/scene_speed.py WORK [--pig-model results/fits/pig_iso.model.zip] [--case cow ...]

The timed scene is benchmarks/scenes.py's pig case (the procedural pig on a floor under an area light, a
bar casting its shadow).  The camera moves around the pig (``to_world`` through ``mi.traverse``), the lamp
moves and changes its colour; each is timed warm (kernels compiled by a first change), median of
``--repeats``, for each of ``--samples`` (irradiance samples a vertex of the first pass; the glow's pass a
quarter of them) and ``--spacing`` (the irradiance traced at every vertex, 0, or on a reduced set); then
the picture's error against a converged irradiance for the same settings (``--no-noise`` leaves it
out).  Then each ``--case`` (default the pig) is rendered at 160 x 120 beside volpath of
the same scene (benchmarks/scenes.py's ``run_case``, a 2 x 64-spp reference kept in WORK): volpath's
seconds at the error ours has over ours (relight + a 16-spp picture), the ratio.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from scenes import ACQUISITIONS, _model, run_case, scene_folder  # noqa: E402 — the benchmark's own scenes
from translucency.experimental import ReducedScene as FittedScene  # noqa: E402 — the reduced irradiance is timed too
from translucency.mitsuba import mitsuba  # noqa: E402
from translucency.scene.compare import object_pixels  # noqa: E402


def _timed(mi, fs, repeats: int) -> tuple[float, float]:
    """Median seconds of a new camera (the picture) and of a new light (the passes and the picture), the
    camera turned and the lamp moved and recoloured each time, after a first change (kernels compiled)."""
    fs.light()
    fs.render(spp=16)
    params = mi.traverse(fs.scene)
    sensor = next(k.removesuffix(".x_fov") for k in params.keys() if k.endswith(".x_fov"))
    cam_key, lamp_key, lamp_rgb = f"{sensor}.to_world", "lamp.to_world", "lamp.emitter.radiance.value"
    camera0, lamp0 = type(params[cam_key])(params[cam_key]), type(params[lamp_key])(params[lamp_key])
    rgb0 = type(params[lamp_rgb])(params[lamp_rgb])
    cams, lights = [], []
    for k in range(repeats + 1):
        params[cam_key] = mi.Transform4f().rotate([0, 0, 1], 10.0 * (k + 1)) @ camera0
        params.update()
        t = time.perf_counter()
        fs.render(spp=16, seed=k)
        cams.append(time.perf_counter() - t)
        params[lamp_key] = mi.Transform4f().translate([5.0 * (k + 1), 0.0, 0.0]) @ lamp0
        params[lamp_rgb] = mi.Color3f(40.0, 40.0 - 3 * k, 40.0 - 6 * k)
        params.update()
        t = time.perf_counter()
        fs.light(seed=k)
        fs.render(spp=16, seed=k)
        lights.append(time.perf_counter() - t)
    params[cam_key], params[lamp_key], params[lamp_rgb] = camera0, lamp0, rgb0
    params.update()
    return statistics.median(cams[1:]), statistics.median(lights[1:])


def noise_of_irradiance(scene, model) -> None:
    """The picture's error against a converged irradiance (512 samples a vertex, every pass, every
    vertex; the same 64-spp picture seed) over the pig's pixels, and a light's seconds, for the samples
    and the reduced vertex set (``irradiance_spacing``)."""
    fs = FittedScene(scene, {"object": model}, samples=512, glow_samples=512)
    fs.prepare()
    objects = object_pixels(fs)
    fs.light(seed=100)
    converged = fs.render(spp=64, seed=5)[objects].mean(axis=-1)
    for spacing in (0.0, 2.0):
        for samples in (16, 32):
            fs.samples, fs.glow_samples, fs.irradiance_spacing = samples, samples // 4, spacing
            seconds = []
            for k in range(4):
                t = time.perf_counter()
                fs.light(seed=7 + k)
                seconds.append(time.perf_counter() - t)
            ours = fs.render(spp=64, seed=5)[objects].mean(axis=-1)
            error = np.sqrt(np.mean((ours - converged) ** 2) / np.mean(converged**2))
            traced = "every vertex" if spacing == 0 else f"{len(fs.reduced[0].traced):,} vertices + edges"
            print(
                f"irradiance {samples} + {samples // 4} samples, traced at {traced}: light "
                f"{statistics.median(seconds[1:]):.3f} s, picture vs converged irradiance {error:.4f}",
                flush=True,
            )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("work", type=Path)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument("--pig-model", type=Path, default=None)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--case", action="append", choices=sorted(ACQUISITIONS), help="scenes against volpath")
    ap.add_argument("--spp-reference", type=int, default=64)
    ap.add_argument("--samples", type=int, nargs="+", default=[16, 32], help="irradiance samples to time")
    ap.add_argument("--spacing", type=float, nargs="+", default=[0.0, 2.0], help="irradiance_spacing to time")
    ap.add_argument("--no-noise", action="store_true", help="leave out the noise against a converged light")
    ap.add_argument("--no-volpath", action="store_true", help="leave out the scenes against volpath")
    args = ap.parse_args()
    mi = mitsuba()
    model = _model("pig", args.work, args.meshes, args.pig_model)
    scene = scene_folder("pig", args.work / "pig-speed", model, (320, 240))
    fs = FittedScene(scene, {"object": model}, samples=args.samples[0])
    t = time.perf_counter()
    fs.prepare()
    print(f"pig ({fs.vertices:,} vertices): prepare {time.perf_counter() - t:.1f} s once", flush=True)
    for samples in args.samples:
        for spacing in args.spacing:
            fs.samples, fs.glow_samples, fs.irradiance_spacing = samples, max(1, samples // 4), spacing
            cam, light = _timed(mi, fs, args.repeats)
            traced = "every vertex" if spacing == 0 else f"one vertex a {spacing:g}-edge cell"
            print(
                f"  320 x 240 at 16 spp, {samples} irradiance samples traced at {traced}: new camera "
                f"{cam:.2f} s; new light {light:.2f} s (target 0.5 s at 27 k vertices, 3 s at 338 k)",
                flush=True,
            )
    if not args.no_noise:
        noise_of_irradiance(scene, model)
    for case in [] if args.no_volpath else args.case or ["pig"]:
        for samples in args.samples:
            row = run_case(
                case, args.work, args.meshes, (160, 120), args.spp_reference, samples, args.pig_model, 64
            )
            print(
                f"{case} ({row['vertices']:,} vertices), 160 x 120, {samples} irradiance samples a vertex: "
                f"object rel. RMSE {row['errors']['object']['rel_rmse']:.3f} (reference noise "
                f"{row['reference_noise']:.3f}); ours {row['relight_s'] + row['draw_s']:.2f} s a light; "
                f"volpath at equal error {row['volpath_equal_error_spp']:.1f} spp: "
                f"{row['speedup_equal_error']:,.0f}x ours (target 1,000x: "
                f"{'met' if row['speedup_equal_error'] >= 1000 else 'not met'})",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
