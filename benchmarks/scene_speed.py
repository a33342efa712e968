"""How fast a fitted object in a scene re-renders after its one-off preparation: a new camera (the
picture only) and a new light (the two passes and the picture), at 320 x 240 and 16 samples a pixel.

    python benchmarks/scene_speed.py WORK [--pig-model results/fits/pig_iso.model.zip]

The scene is benchmarks/scenes.py's pig case (the procedural pig on a floor under an area light, a bar
casting its shadow).  The camera moves around the pig (``to_world`` through ``mi.traverse``), the lamp
moves and changes its colour; each is timed warm (kernels compiled by a first change), median of 5.
The irradiance's samples per vertex trade time for noise: at 16 the picture differs from a converged
irradiance by 0.026 (relative RMSE over the pig), at 32 by 0.018, at 64 by 0.014 (measured on this pig).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from scenes import _model, scene_folder  # noqa: E402 — the benchmark's own scenes
from translucency.mitsuba import mitsuba  # noqa: E402
from translucency.scene import FittedScene  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("work", type=Path)
    ap.add_argument("--meshes", type=Path, default=Path("../shared/meshes"))
    ap.add_argument("--pig-model", type=Path, default=None)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    mi = mitsuba()
    model = _model("pig", args.work, args.meshes, args.pig_model)
    scene = scene_folder("pig", args.work / "pig-speed", model, (320, 240))
    for samples in (16, 32):
        fs = FittedScene(scene, {"object": model}, samples=samples)
        t = time.perf_counter()
        fs.prepare()
        prepare = time.perf_counter() - t
        fs.light()
        fs.render(spp=16)
        params = mi.traverse(fs.scene)
        sensor = next(k.removesuffix(".x_fov") for k in params.keys() if k.endswith(".x_fov"))
        cam_key, lamp_key, lamp_rgb = f"{sensor}.to_world", "lamp.to_world", "lamp.emitter.radiance.value"
        camera0, lamp0 = type(params[cam_key])(params[cam_key]), type(params[lamp_key])(params[lamp_key])
        cams, lights = [], []
        for k in range(args.repeats + 1):
            turn = mi.Transform4f().rotate([0, 0, 1], 10.0 * (k + 1))
            params[cam_key] = turn @ camera0
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
        cam, light = statistics.median(cams[1:]), statistics.median(lights[1:])
        print(
            f"pig ({fs.vertices:,} vertices), 320 x 240 at 16 spp, {samples} irradiance samples a vertex: "
            f"prepare {prepare:.1f} s once; new camera {cam:.2f} s; new light {light:.2f} s "
            f"(target 2 s: {'met' if max(cam, light) <= 2 else 'not met'})",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
