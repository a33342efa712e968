"""Throughput of ``import object`` (issue 23's target: ≥ 100 MB/s of images on 2 cores), beside the
plain reading of the same files (the ceiling: decoding PFM and nothing else).

    python benchmarks/object_import_throughput.py [SHOTS] [CAMERAS] [WIDTH] [HEIGHT]

Writes a synthetic rig (an icosphere of 40,962 vertices, cameras around it, two frames per camera and
shot of a smooth exitance field) into a temporary folder, imports it twice (cold: visibility and maps;
the second, resumed from nothing, the same) and prints MB/s of images for the import and for reading.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

from translucency.io.atomic import write_json
from translucency.rig.object.cameras import Camera
from translucency.rig.object.importer import import_object
from translucency.rig.object.photographs import cameras_around
from translucency.rig.object.surface_map import surface_map
from translucency.rig.shared.hdr import read_hdr, write_pfm


def synthetic_rig(folder: Path, shots: int, n_cam: int, width: int, height: int) -> list[Path]:
    mesh = trimesh.creation.icosphere(subdivisions=6, radius=20.0)
    mesh.export(folder / "object.ply")
    cams: list[Camera] = cameras_around(mesh, n_cam, width, height)
    hits = mesh.vertices[np.linspace(0, len(mesh.vertices) - 1, shots).astype(int)]
    files, entries, shot_entries = (
        [],
        [],
        [{"hit": {"point": h.tolist()}, "power": 1.0, "images": {}} for h in hits],
    )
    for c in cams:
        m = surface_map(mesh, c)
        entries.append(
            {
                "name": c.name,
                "width": width,
                "height": height,
                "intrinsics": {"K": c.K.tolist(), "dist": c.dist.tolist()},
                "pose": {"R": c.R.tolist(), "t": c.t.tolist()},
                "radiometry": {"k": 1e3, "gain": 0.01, "read_noise": 0.01, "saturation": 1e9},
            }
        )
        for j, h in enumerate(hits):
            d = np.linalg.norm(np.nan_to_num(m.position, nan=1e3) - h, axis=1)
            img = (
                (1e3 * np.exp(-d / 3.0) / 8.0).reshape(height, width, 1).repeat(3, axis=2).astype(np.float32)
            )
            frames = []
            for rep in range(2):
                name = f"s{j:03d}_{c.name}_{rep}.pfm"
                write_pfm(folder / name, img)
                files.append(folder / name)
                frames.append({"file": name, "exposure_s": 1.0})
            shot_entries[j]["images"][c.name] = frames
    write_json(
        folder / "object.json",
        {
            "format": "translucency-object-rig",
            "version": 1,
            "mesh": {"file": "object.ply"},
            "boundary": {"eta": 1.0},
            "exit_law": "lambertian",
            "cameras": entries,
            "shots": shot_entries,
        },
    )
    return files


def main(argv) -> None:
    shots, n_cam, width, height = (
        int(v) for v in (argv[1:] + ["32", "4", "512", "384"][len(argv) - 1 :])[:4]
    )
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        files = synthetic_rig(folder, shots, n_cam, width, height)
        mb = sum(f.stat().st_size for f in files) / 2**20
        t = time.perf_counter()
        for f in files:
            read_hdr(f)
        read_s = time.perf_counter() - t
        info = import_object(folder, folder / "out.zarr", chunk_points=8)
        print(
            json.dumps(
                {
                    "images_MB": mb,
                    "shots": shots,
                    "cameras": n_cam,
                    "size": [width, height],
                    "import_s": info["seconds"],
                    "import_MB_s": mb / info["seconds"],
                    "read_only_MB_s": mb / read_s,
                    "ratio_import_to_read": read_s / info["seconds"],
                }
            )
        )


if __name__ == "__main__":
    main(sys.argv)
