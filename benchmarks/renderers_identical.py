"""Every renderer's picture as bytes: ``render`` (lights from the front, the side and behind, ``--paper``,
``--angles``), a scene (``render scene``), the viewer's exported page and the glTF bake, for each model
given — hashed, so that a change that must not move a number (a refactor) can be held to it.

    python benchmarks/renderers_identical.py OUT.json MODEL [MODEL ...] --scene SCENE.xml
    python benchmarks/renderers_identical.py NEW.json MODEL ... --scene SCENE.xml --against OLD.json [...]

Prints one line per picture (its SHA-256 and, with ``--against``, ``bit-identical`` to one of the earlier
runs or its largest difference over the peak, beside the earlier runs' own difference among themselves)
and exits 1 if any differs by more than ``--tolerance``.  The models are per-vertex model files
(``translucency fit`` on a mesh data set); the scene places the first of them as its shape ``object``
(``translucency export --ply``).
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


def _largest_difference(a, b) -> float:
    """The largest difference of two pictures over the first's peak (inf where they cannot be compared)."""
    if a.shape != b.shape or a.dtype.kind != "f":
        return float("inf")
    return float(np.max(np.abs(a - b)) / max(float(np.max(np.abs(a))), 1e-30))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("models", type=Path, nargs="+")
    ap.add_argument("--scene", type=Path)
    ap.add_argument("--against", type=Path, nargs="+", help="earlier runs' JSON (their .npz beside them)")
    ap.add_argument(
        "--tolerance",
        type=float,
        default=0.0,
        help="largest difference over the peak counted as the same (0: bit for bit). Mitsuba's picture of a "
        "dielectric object is not bit-reproducible between two runs of the same code (~2e-8 of the peak)",
    )
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        got = pictures(args.models, args.scene, Path(tmp))
    np.savez_compressed(args.out.with_suffix(".npz"), **{k.replace("/", "__"): v for k, v in got.items()})
    hashes = {k: _digest(v) for k, v in got.items()}
    args.out.write_text(json.dumps(hashes, indent=1))
    if not args.against:
        for k, h in hashes.items():
            print(f"{k:40s} {h}")
        return 0
    runs = [(json.loads(f.read_text()), np.load(f.with_suffix(".npz"))) for f in args.against]
    identical = within = 0
    for k, h in hashes.items():
        key = k.replace("/", "__")
        if any(old.get(k) == h for old, _ in runs):
            identical += 1
            print(f"{k:40s} {h} bit-identical")
            continue
        ours = min(_largest_difference(arrays[key], got[k]) for _, arrays in runs)
        # the earlier runs against each other: the renderer's own run-to-run difference
        own = [_largest_difference(a[key], b[key]) for i, (_, a) in enumerate(runs) for _, b in runs[i + 1 :]]
        spread = f"; the earlier runs differ by {max(own):.3g} among themselves" if own else ""
        print(f"{k:40s} {h} differs by {ours:.3g} of the peak{spread}")
        within += ours <= args.tolerance
    print(f"{identical} of {len(hashes)} pictures bit-identical, {within} more within {args.tolerance:g}")
    return 0 if identical + within == len(hashes) else 1


if __name__ == "__main__":
    sys.exit(main())
