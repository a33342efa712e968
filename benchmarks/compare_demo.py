"""Are two `translucency demo` output folders the same numbers? (a refactoring's check: bit-identical results)

    python benchmarks/compare_demo.py BASELINE_DIR NEW_DIR

Compares every JSON summary (report.json, figure2.json, relight.json, baselines.json; timing fields and paths
ignored), every model file's arrays (SHA-256 of each stored chunk) and headers, the EXR pictures and the
per-vertex data set ``pig.zarr`` byte for byte. Prints IDENTICAL, or DIFFERENT with the first 60 differences
(exit status 1).
"""

from __future__ import annotations

import hashlib
import json
import sys
import zipfile
from pathlib import Path

#: keys whose values are times, dates or machine facts: not results
TIMING = {"seconds", "time_estimate", "estimate", "created", "date", "elapsed"}


def _is_timing(key) -> bool:
    key = str(key)
    return key in TIMING or key.endswith("_s") or key.startswith("speedup")


def compare_json(a, b, where: str, errors: list) -> None:
    """Every difference of two JSON values, one line each, into ``errors`` (paths and timings ignored)."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if _is_timing(k):
                continue
            if k not in a or k not in b:
                errors.append(f"{where}.{k}: only in {'new' if k in b else 'baseline'}")
            else:
                compare_json(a[k], b[k], f"{where}.{k}", errors)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            errors.append(f"{where}: length {len(a)} != {len(b)}")
            return
        for i, (x, y) in enumerate(zip(a, b)):
            compare_json(x, y, f"{where}[{i}]", errors)
    elif isinstance(a, str) and isinstance(b, str) and ("/" in a or "/" in b):
        return  # paths differ between output folders
    elif a != b:
        errors.append(f"{where}: {a!r} != {b!r}")


def _zip_entries(path: Path) -> dict:
    """A model file's entries: the JSON of its metadata, the SHA-256 of every chunk."""
    out = {}
    with zipfile.ZipFile(path) as z:
        for name in sorted(z.namelist()):
            data = z.read(name)
            out[name] = ("json", json.loads(data)) if name.endswith("zarr.json") else ("bytes", _sha(data))
    return out


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def compare(a: Path, b: Path) -> list[str]:
    """The differences between demo folders ``a`` (baseline) and ``b``."""
    errors: list[str] = []
    for f in sorted(a.rglob("*.json")):
        rel = f.relative_to(a)
        if rel.name == ".translucency-output.json" or "pig.zarr" in rel.parts:
            continue
        if not (b / rel).exists():
            errors.append(f"{rel}: missing")
            continue
        compare_json(json.loads(f.read_text()), json.loads((b / rel).read_text()), str(rel), errors)
    for f in sorted(a.rglob("*.model.zip")):
        rel = f.relative_to(a)
        if not (b / rel).exists():
            errors.append(f"{rel}: missing")
            continue
        za, zb = _zip_entries(f), _zip_entries(b / rel)
        if set(za) != set(zb):
            errors.append(f"{rel}: entries differ {sorted(set(za) ^ set(zb))}")
        for name in sorted(set(za) & set(zb)):
            if za[name][0] == "json":
                compare_json(za[name][1], zb[name][1], f"{rel}:{name}", errors)
            elif za[name] != zb[name]:
                errors.append(f"{rel}:{name}: array bytes differ")
    binaries = [*a.rglob("*.exr"), *(p for p in (a / "pig.zarr").rglob("*") if p.is_file())]
    for f in sorted(binaries):
        rel = f.relative_to(a)
        if rel.name == "zarr.json":
            continue
        if not (b / rel).exists() or f.read_bytes() != (b / rel).read_bytes():
            errors.append(f"{rel}: differs")
    return errors


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(__doc__)
        return 2
    errors = compare(Path(argv[0]), Path(argv[1]))
    if errors:
        print(f"DIFFERENT: {len(errors)} differences")
        for e in errors[:60]:
            print("  ", e)
        return 1
    print("IDENTICAL (timings ignored)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
