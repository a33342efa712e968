"""The object rig end to end (issue 23): virtual photographs of an object → ``import object`` → recovery,
energy and render error against the photon tally of the same object, with the import's throughput.

    python benchmarks/object_rig.py sphere   # a 6 mm skin sphere (fast: a few minutes)
    python benchmarks/object_rig.py sphere24 # the same sphere, 24 cameras (12 min)
    python benchmarks/object_rig.py pig      # the main job's pig in marble
    python benchmarks/object_rig.py cow PATH/cow.obj
    python benchmarks/object_rig.py torus        # a skin torus (not convex)

Prints one JSON object per case (docs/object-rig.md quotes them).
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np
import trimesh

from translucency.acquire.mesh import object_volume
from translucency.acquire.objects import make_pig
from translucency.io.mesh import load_mesh
from translucency.pipeline.object_rig_check import object_rig_check

CASES = {
    "sphere": dict(material="homogeneous:skin1", points=4, cameras=8, resolution=(96, 96), spp=256),
    # the same sphere seen by a denser rig (each vertex by ~10 cameras): how the figures go with the views
    "sphere24": dict(material="homogeneous:skin1", points=4, cameras=24, resolution=(96, 96), spp=128),
    "pig": dict(material="marble", points=4, cameras=6, resolution=(96, 72), spp=64),
    "cow": dict(material="skin", points=4, cameras=8, resolution=(128, 96), spp=128),
    "torus": dict(material="skin", points=4, cameras=8, resolution=(96, 96), spp=192),
}


def main(argv) -> None:
    name = argv[1] if len(argv) > 1 else "sphere"
    case = dict(CASES[name])
    if name.startswith("sphere"):
        mesh = trimesh.creation.icosphere(subdivisions=4, radius=6.0)
    elif name == "pig":
        mesh = make_pig()
    elif name == "torus":  # not convex: the import's visibility is tested where the object hides itself
        mesh = trimesh.creation.torus(
            major_radius=8.0, minor_radius=3.5, major_sections=96, minor_sections=48
        )
    else:
        mesh = load_mesh(argv[2], scale_mm=10.0)
    volume = object_volume(case.pop("material"), mesh, 0.5 if name != "pig" else 1.0, seed=1)
    folder = Path(argv[3]) if len(argv) > 3 else Path(tempfile.mkdtemp(prefix=f"object-rig-{name}-"))
    reuse = "--reuse" in argv
    law = next((a.split("=", 1)[1] for a in argv if a.startswith("--exit-law=")), None)
    out = object_rig_check(
        mesh, volume, folder, reuse=reuse, exit_law=law, progress=lambda t: print(t, file=sys.stderr), **case
    )
    out["throughput_MB_s"] = out["import_MB"] / out["import_seconds"]
    out["case"] = name
    out.pop("exit_law")
    print(json.dumps(out, default=lambda x: np.asarray(x).tolist()))


if __name__ == "__main__":
    main(sys.argv)
