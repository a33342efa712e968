"""Damaged data sets (issue 14, item 2): missing or corrupt chunks are found, said in one line, and an
acquisition run again repairs exactly those, bit for bit."""

import hashlib

import numpy as np
import pytest
from typer.testing import CliRunner

from translucency._validate import TranslucencyError
from translucency.cli.app import app
from translucency.io.dataset import PlanarDataset, open_dataset
from translucency.io.datasets import open_any_dataset
from translucency.io.mesh_dataset import MeshDataset, open_mesh_dataset

runner = CliRunner()
ARGS = [
    "acquire",
    "planar",
    "--material",
    "marble",
    "--grid",
    "2",
    "--span",
    "2",
    "--photons",
    "400",
    "--size",
    "8",
    "8",
    "3",
    "--voxel",
    "0.5",
    "--window",
    "4",
    "--pitch",
    "0.5",
    "--chunk",
    "2",
]


def _digest(path):
    return hashlib.sha256(np.ascontiguousarray(open_dataset(path)["R_d"]).tobytes()).hexdigest()


@pytest.fixture
def scan(tmp_path):
    out = tmp_path / "s.zarr"
    res = runner.invoke(app, [*ARGS, "--out", str(out)])
    assert res.exit_code == 0, res.output
    return out


def test_a_missing_chunk_is_found_and_repaired(scan):
    before = _digest(scan)
    (scan / "R_d" / "c" / "1" / "0" / "0" / "0").unlink()  # the second chunk of points
    assert open_dataset(scan).damaged_chunks() == {"R_d": [1]}
    info = runner.invoke(app, ["info", str(scan)])
    assert info.exit_code == 0 and "R_d chunks [1]" in info.output
    fit = runner.invoke(app, ["fit", str(scan), "--out", str(scan.parent / "m.model.zip")])
    assert fit.exit_code == 2 and "unfinished" in fit.output  # no zeros fitted
    res = runner.invoke(app, [*ARGS, "--out", str(scan)])
    assert res.exit_code == 0, res.output
    assert "warning:" in res.output and "chunks [1]" in res.output  # one line, not a Python warning
    assert open_dataset(scan).damaged_chunks() == {} and _digest(scan) == before


def test_a_truncated_chunk_is_one_line(scan):
    (scan / "R_d" / "c" / "0" / "0" / "0" / "0").write_bytes(b"0123456789")
    assert open_dataset(scan).damaged_chunks() == {"R_d": [0]}
    res = runner.invoke(app, ["fit", str(scan), "--out", str(scan.parent / "m.model.zip")])
    lines = [ln for ln in res.output.strip().splitlines() if ln.strip()]
    assert res.exit_code == 2 and lines[-1].startswith("error:") and "'R_d'" in lines[-1], res.output
    assert "Traceback" not in res.output


def test_a_second_writer_is_stopped_and_a_stale_lock_taken_over(tmp_path):
    import os
    import subprocess
    import sys

    out = tmp_path / "s.zarr"
    lock = tmp_path / ".s.zarr.lock"
    lock.write_text(str(os.getppid()))  # a live process holds it
    res = runner.invoke(app, [*ARGS, "--out", str(out)])
    assert res.exit_code == 2 and "another translucency process" in res.output and not out.exists()
    gone = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True
    )
    lock.write_text(gone.stdout.strip())  # its writer has exited: stale
    res = runner.invoke(app, [*ARGS, "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert open_dataset(out).complete() and not lock.exists()


MESH_ARGS = [
    "acquire",
    "mesh",
    "--material",
    "homogeneous:marble",
    "--voxel",
    "1",
    "--points",
    "4",
    "--photons",
    "200",
    "--chunk",
    "2",
    "--index-matched",
]


def _mesh_digest(path):
    ds = open_mesh_dataset(path)
    return hashlib.sha256(
        b"".join(np.ascontiguousarray(ds[k]).tobytes() for k in ("R_d", "vertices"))
    ).hexdigest()


@pytest.fixture
def mesh_scan(tmp_path):
    import trimesh

    ball = tmp_path / "ball.ply"
    trimesh.creation.icosphere(1, radius=4.0).export(ball)
    out = tmp_path / "b.zarr"
    args = [*MESH_ARGS, "--mesh", str(ball), "--out", str(out)]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    return out, args


@pytest.mark.parametrize(
    "damage,array,chunk",
    [
        (lambda s: (s / "R_d" / "c" / "1" / "0" / "0").unlink(), "R_d", 1),
        (lambda s: (s / "R_d" / "c" / "0" / "0" / "0").write_bytes(b"0123456789"), "R_d", 0),
        (lambda s: (s / "specular" / "c" / "1" / "0").write_bytes(b"\x00" * 7), "specular", 1),
        (lambda s: (s / "vertices" / "c" / "0" / "0").unlink(), "vertices", 0),
    ],
)
def test_a_damaged_mesh_data_set_is_found_and_repaired(mesh_scan, damage, array, chunk):
    out, args = mesh_scan
    before = _mesh_digest(out)
    damage(out)
    assert open_mesh_dataset(out).damaged_chunks() == {array: [chunk]}
    info = runner.invoke(app, ["info", str(out)])
    assert info.exit_code == 0 and f"{array} chunks [{chunk}]" in info.output, info.output
    fit = runner.invoke(app, ["fit", str(out), "--out", str(out.parent / "m.model.zip")])
    lines = [ln for ln in fit.output.strip().splitlines() if ln.strip()]
    assert fit.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error:"), fit.output
    assert f"'{array}' chunks [{chunk}]" in fit.output.replace("\n", "")
    res = runner.invoke(app, args)
    assert res.exit_code == 0 and "warning:" in res.output, res.output
    assert open_mesh_dataset(out).damaged_chunks() == {} and _mesh_digest(out) == before


def test_one_opener_tells_the_kinds_apart(scan, mesh_scan):
    """Each data set opens as its kind through the one opener; the other kind's reader names what it is."""
    mesh = mesh_scan[0]
    assert type(open_any_dataset(scan)) is PlanarDataset and type(open_any_dataset(mesh)) is MeshDataset
    with pytest.raises(TranslucencyError, match="b.zarr: a mesh data set, where a planar data set is needed"):
        open_dataset(mesh)
    with pytest.raises(TranslucencyError, match="s.zarr: a planar data set, where a mesh data set is needed"):
        open_mesh_dataset(scan)
    with pytest.raises(TranslucencyError, match="nothing.zarr: no such data set"):
        open_any_dataset(scan.parent / "nothing.zarr")
