"""What a planar import records and compares on resume: the files' SHA-256, the calibration, the setup."""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict
from pathlib import Path

import numpy as np

from ..._version import __version__
from ...io.dataset import FORMAT, VERSION
from ..contract import sha256_file


def import_header(
    folder: Path, table, shots: list, calibration, setup, x_i: np.ndarray, *, views=(), workers: int = 1
) -> dict:
    """The planar data set's header of an import: format, grid, sample, acquisition, the provenance of
    every image (path relative to its folder, SHA-256, laser power, exposures; every further view's
    likewise) and the ``request`` compared on resume (setup, hashes, calibrations, positions in mm).

    ``table``: the positions' file (None when given as rows); ``views``: (folder, table, shots,
    Calibration) of each further camera; ``workers``: files hashed at once (threads).
    """
    digest = _digests(shots, workers)
    hashes = [[digest[f] for f in s.files] for s in shots]
    view_provenance = [_view_provenance(*view, workers) for view in views]
    provenance = {
        "folder": str(folder.resolve()),
        "positions": None if table is None else {"file": str(table), "sha256": sha256_file(table)},
        "files": [[str(f.relative_to(folder)) for f in s.files] for s in shots],
        "sha256": hashes,
        "power_W": [s.power for s in shots],
        "exposure_s": [list(s.exposures) for s in shots],
        "position_units": shots[0].units,
        "calibration": calibration.describe(),
    }
    if view_provenance:
        provenance["views"] = view_provenance
    request = _request(setup, hashes, calibration, view_provenance, x_i)
    return {
        "format": FORMAT,
        "version": VERSION,
        "units": {"length": "mm", "R_d": "mm^-2", "variance": "mm^-4"},
        "pitch_mm": setup.pitch,
        "window": [setup.window_pixels(), setup.window_pixels()],
        "n_points": len(shots),
        "chunk_points": setup.chunk_points,
        "dtype": setup.dtype,
        "sample": {
            "eta": setup.eta,
            "size_mm": None if setup.sample_size is None else list(setup.sample_size),
            "description": {"source": "rig photographs", "folder": str(folder)},
        },
        "acquisition": {
            "photons": None,
            "estimator": "HDR photographs, homography resampling",
            "noise_model": "repeated frames" if any(len(s.files) > 1 for s in shots) else "gain + read",
        },
        "provenance": provenance,
        "software": {"translucency": __version__},
        "request": request,
    }


def _digests(shots: list, workers: int) -> dict:
    """The SHA-256 of every shot's every file, ``workers`` files hashed at once."""
    flat = [f for s in shots for f in s.files]
    with ThreadPoolExecutor(workers) as pool:  # reading, hashing and NumPy release the GIL: in parallel
        return dict(zip(flat, pool.map(sha256_file, flat)))


def _view_provenance(v_folder: Path, v_table, v_shots: list, v_calib, workers: int) -> dict:
    """A further camera's provenance: its folder, positions' file, images' SHA-256, powers, calibration."""
    v_digest = _digests(v_shots, workers)
    return {
        "folder": str(v_folder.resolve()),
        "positions": None if v_table is None else {"file": str(v_table), "sha256": sha256_file(v_table)},
        "files": [[str(f.relative_to(v_folder)) for f in sh.files] for sh in v_shots],
        "sha256": [[v_digest[f] for f in sh.files] for sh in v_shots],
        "power_W": [sh.power for sh in v_shots],
        "calibration": v_calib.describe(),
    }


def _request(setup, hashes: list, calibration, view_provenance: list, x_i: np.ndarray) -> dict:
    """What a resume compares (JSON round-tripped): setup, hashes, calibrations and positions (mm)."""
    request = json.loads(
        json.dumps(
            {
                "setup": asdict(setup),
                "sha256": hashes,
                "calibration": calibration.describe(),
                "views": [[v["sha256"], v["calibration"]] for v in view_provenance],
            }
        )
    )
    request["positions"] = x_i.round(9).tolist()
    return request
