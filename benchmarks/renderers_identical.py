"""Every renderer's picture as bytes: ``render`` (lights from the front, the side and behind, ``--paper``,
``--angles``), a scene (``render scene``), the viewer's exported page and the glTF bake, for each model
given — hashed, so that a change that must not move a number (a refactor) can be held to it.

    python benchmarks/renderers_identical.py OUT.json MODEL [MODEL ...] --scene SCENE.xml
    python benchmarks/renderers_identical.py NEW.json MODEL ... --scene SCENE.xml --against OLD.json

Prints one line per picture (its SHA-256 and, with ``--against``, ``same`` or the largest relative
difference) and exits 1 if any differs.  The models are per-vertex model files (``translucency fit`` on a
mesh data set); the scene places the first of them as its shape ``object`` (``translucency export --ply``).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

import translucency as tl

#: the lights of ``render`` (relative to the object: front, side, behind) and what else varies
RENDERS = {
    "front": dict(light="point@camera"),
    "side": dict(light="directional@90,10"),
    "back": dict(light="point@back"),
    "paper": dict(light="point@back", paper=True),
    "angles": dict(light="point@back", angles=True),
    "default-light": dict(),
}


def _digest(array) -> str:
    return hashlib.sha256(np.ascontiguousarray(array).tobytes()).hexdigest()[:16]


def pictures(models: list[Path], scene: Path | None, work: Path) -> dict[str, np.ndarray]:
    """name → array (or bytes as uint8) of every renderer's output."""
    out: dict[str, np.ndarray] = {}
    for model in models:
        key = model.name.removesuffix(".model.zip")
        for name, kw in RENDERS.items():
            shot = tl.render_model(model, resolution=(96, 72), **kw)
            out[f"{key}/render/{name}"] = shot.picture
        page = work / f"{key}-page"
        tl.view_model(model, page, open_browser=False)
        out[f"{key}/view/data.js"] = np.frombuffer((page / "data.js").read_bytes(), np.uint8)
        glb = work / f"{key}.glb"
        tl.export_model(model, gltf=glb)
        out[f"{key}/gltf"] = np.frombuffer(glb.read_bytes(), np.uint8)
    if scene is not None:
        shot = tl.render_scene(scene, {"object": models[0]}, work / "scene", samples=8, picture_spp=4)
        out["scene/ours"] = shot.picture
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("models", type=Path, nargs="+")
    ap.add_argument("--scene", type=Path)
    ap.add_argument("--against", type=Path)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        got = pictures(args.models, args.scene, Path(tmp))
    np.savez_compressed(args.out.with_suffix(".npz"), **{k.replace("/", "__"): v for k, v in got.items()})
    hashes = {k: _digest(v) for k, v in got.items()}
    args.out.write_text(json.dumps(hashes, indent=1))
    if args.against is None:
        for k, h in hashes.items():
            print(f"{k:40s} {h}")
        return 0
    old = json.loads(args.against.read_text())
    old_arrays = np.load(args.against.with_suffix(".npz"))
    differ = 0
    for k, h in hashes.items():
        if k not in old:
            print(f"{k:40s} {h} (new)")
            continue
        if old[k] == h:
            print(f"{k:40s} {h} same")
            continue
        differ += 1
        a, b = old_arrays[k.replace("/", "__")], got[k]
        if a.shape == b.shape and a.dtype.kind == "f":
            rel = float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(a))), 1e-30))
            print(f"{k:40s} {h} DIFFERS (largest difference {rel:.3g} of the peak)")
        else:
            print(f"{k:40s} {h} DIFFERS ({a.shape} {a.dtype} -> {b.shape} {b.dtype})")
    print(f"{len(hashes) - differ} of {len(hashes)} pictures identical")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
