"""Planar acquisitions write every chunk as a file, all-zero ones included (issue 16 follow-up).

Zarr's ``write_empty_chunks`` is a runtime setting, not saved with an array: a store opened again skips
chunks holding only the fill value, and a missing chunk file then reads as zeros, silently.  An
index-matched slab has no specular reflection, so its ``specular`` chunks are all zero.
"""

import hashlib

import numpy as np
import pytest

from translucency.acquire import PlanarSetup, acquire_planar, make_sample
from translucency.io.dataset import open_dataset

SETUP = PlanarSetup(
    grid=(4, 4),
    span=(6.0, 6.0),
    pitch=0.5,
    window=6.0,
    photons=300,
    seed=3,
    chunk_points=4,
    index_matched=True,
)
PER_POINT = ("R_d", "variance", "mask", "specular", "total_diffuse")


@pytest.fixture(scope="module")
def volume():
    return make_sample("marble", (12, 12, 4), 0.5, seed=1)


@pytest.fixture
def scan(tmp_path, volume):
    return acquire_planar(volume, SETUP, tmp_path / "s.zarr")


def _files(ds, name):
    return sorted(p.relative_to(ds.path / name) for p in (ds.path / name / "c").rglob("*") if p.is_file())


def _digest(ds):
    h = hashlib.sha256()
    for name in (*PER_POINT, "chunk_done"):
        h.update(np.ascontiguousarray(ds[name]).tobytes())
    return h.hexdigest()


def test_every_chunk_is_a_file_all_zero_ones_too(scan):
    assert not np.asarray(scan["specular"]).any()  # index matched: no specular reflection at all
    n_chunks = -(-scan.n_points // SETUP.chunk_points)
    for name in (*PER_POINT, "chunk_done"):
        assert len(_files(scan, name)) == n_chunks, name
    assert scan.header["chunk_files"] == "every"


def test_a_deleted_all_zero_chunk_is_found_and_repaired(scan, volume):
    before = _digest(scan)
    (scan.path / "specular" / "c" / "1" / "0").unlink()  # all zero: reads back the same without its file
    assert open_dataset(scan.path).damaged_chunks() == {"specular": [1]}
    assert not open_dataset(scan.path).complete()
    with pytest.warns(UserWarning, match=r"chunks \[1\]"):
        again = acquire_planar(volume, SETUP, scan.path)
    assert again.damaged_chunks() == {} and again.complete()
    assert (scan.path / "specular" / "c" / "1" / "0").is_file() and _digest(again) == before
