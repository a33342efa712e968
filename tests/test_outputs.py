"""Nothing the tool did not write is ever replaced or deleted, whatever the flags (docs/reliability.md).

Each test puts a user's own file or folder where a command writes and runs
every writing command against it, with and without ``--overwrite``: the
command must refuse in one ``error:`` line with status 2 and leave every byte
of the user's files as it was.
"""

import hashlib
import json

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

from helpers import random_exponential_model
from translucency import TranslucencyError, save_model
from translucency.cli.app import app
from translucency.io.dataset import write_dataset
from translucency.io.outputs import MARKER, claim_output, kind_of, remove_dataset

runner = CliRunner()


def snapshot(folder):
    """Every file below ``folder`` with the hash of its bytes."""
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def refused(res, *, recommends_overwrite=False):
    lines = [ln for ln in res.output.strip().splitlines() if ln.strip()]
    assert res.exit_code == 2, res.output
    assert lines[-1].startswith("error:") and "Traceback" not in res.output, res.output
    assert ("--overwrite" in lines[-1]) == recommends_overwrite, lines[-1]
    return lines[-1]


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """A small planar data set, a planar model file and a per-vertex model of a ball (with its data set)."""
    root = tmp_path_factory.mktemp("inputs")
    rng = np.random.default_rng(3)
    ds = write_dataset(
        root / "d.zarr", [[2.0, 2.0]], [[0.0, 0.0]], rng.uniform(0.01, 0.1, (1, 16, 16, 3)), 0.25
    )
    model = save_model(random_exponential_model(rng, n_points=1), root / "m.model.zip")
    mesh = root / "ball.ply"
    trimesh.creation.icosphere(2, radius=4.0).export(mesh)
    mdata, mmodel = root / "ball.zarr", root / "ball.model.zip"
    res = runner.invoke(
        app,
        [
            "acquire",
            "mesh",
            "--out",
            str(mdata),
            "--mesh",
            str(mesh),
            "--material",
            "homogeneous:marble",
            "--voxel",
            "1",
            "--points",
            "4",
            "--photons",
            "300",
            "--index-matched",
        ],
    )
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["fit", str(mdata), "--out", str(mmodel), "--rounds", "1"])
    assert res.exit_code == 0, res.output
    return {"data": ds.path, "model": model, "mesh": mesh, "mesh_data": mdata, "mesh_model": mmodel}


def writers(inp, out):
    """Every writing command, its output at ``out``."""
    acquire = ["--photons", "100", "--overwrite"]
    return {
        "acquire planar": [
            "acquire",
            "planar",
            "--material",
            "marble",
            "--grid",
            "1",
            "--size",
            "6",
            "6",
            "2",
            "--voxel",
            "1",
            "--window",
            "2",
            "--out",
            str(out),
            *acquire,
        ],
        "acquire mesh": [
            "acquire",
            "mesh",
            "--mesh",
            str(inp["mesh"]),
            "--voxel",
            "2",
            "--points",
            "2",
            "--out",
            str(out),
            *acquire,
        ],
        "fit": ["fit", str(inp["data"]), "--out", str(out), "--overwrite"],
        "render": [
            "render",
            str(inp["mesh_model"]),
            "--out",
            str(out),
            "--resolution",
            "16",
            "12",
            "--overwrite",
        ],
        "evaluate --report": [
            "evaluate",
            str(inp["model"]),
            str(inp["data"]),
            "--report",
            str(out),
            "--overwrite",
        ],
        "evaluate --json-out": [
            "evaluate",
            str(inp["model"]),
            str(inp["data"]),
            "--report",
            str(out) + ".report",
            "--json-out",
            str(out),
            "--overwrite",
        ],
        "demo": ["demo", "--out", str(out), "--overwrite"],
    }


def test_overwrite_never_deletes_the_current_folder(inputs, tmp_path, monkeypatch):
    work = tmp_path / "my work"
    (work / "chapter").mkdir(parents=True)
    (work / "thesis.tex").write_text("\\documentclass{article}")
    (work / "chapter" / "data.csv").write_text("1,2,3\n")
    before = snapshot(work)
    monkeypatch.chdir(work)
    for name, args in writers(inputs, ".").items():
        if name == "evaluate --json-out":
            continue  # --json . names a folder: covered below
        msg = refused(runner.invoke(app, args))
        assert "current folder" in msg, (name, msg)
        assert snapshot(work) == before, name
    for name, args in writers(inputs, "chapter").items():  # a user's folder below the current one
        refused(runner.invoke(app, args))
        assert snapshot(work) == before, name


def test_overwrite_never_replaces_a_users_file(inputs, tmp_path):
    thesis = tmp_path / "thesis.tex"
    thesis.write_text("\\documentclass{article} years of work")
    before = snapshot(tmp_path)
    for name, args in writers(inputs, thesis).items():
        msg = refused(runner.invoke(app, args))
        assert "thesis.tex" in msg and "not a translucency" in msg, (name, msg)
        assert snapshot(tmp_path) == before, name
        # and without --overwrite the message does not suggest it either
        refused(runner.invoke(app, [a for a in args if a != "--overwrite"]))
        assert snapshot(tmp_path) == before, name


def test_an_input_is_never_an_output(inputs):
    before = snapshot(inputs["data"])
    res = runner.invoke(app, ["fit", str(inputs["data"]), "--out", str(inputs["data"]), "--overwrite"])
    assert "input" in refused(res)
    res = runner.invoke(
        app,
        [
            "evaluate",
            str(inputs["model"]),
            str(inputs["data"]),
            "--report",
            str(inputs["data"] / "report"),
            "--overwrite",
        ],
    )
    assert "input" in refused(res)
    res = runner.invoke(
        app, ["render", str(inputs["mesh_model"]), "--out", str(inputs["mesh_data"]), "--overwrite"]
    )
    refused(res)
    assert snapshot(inputs["data"]) == before


def test_own_outputs_are_replaced_only_with_overwrite(inputs, tmp_path):
    out = tmp_path / "iso.model.zip"
    args = ["fit", str(inputs["data"]), "--out", str(out), "--rounds", "1"]
    assert runner.invoke(app, args).exit_code == 0
    first = out.read_bytes()
    msg = refused(runner.invoke(app, args), recommends_overwrite=True)
    assert "already there" in msg and out.read_bytes() == first
    res = runner.invoke(app, [*args, "--overwrite"])
    assert res.exit_code == 0, res.output
    assert kind_of(out) == "model file"
    # a render folder: created with the marker, reused only with --overwrite
    render = ["render", str(inputs["mesh_model"]), "--out", str(tmp_path / "r"), "--resolution", "16", "12"]
    assert runner.invoke(app, render).exit_code == 0
    assert kind_of(tmp_path / "r") == "output folder" and (tmp_path / "r" / MARKER).is_file()
    refused(runner.invoke(app, render), recommends_overwrite=True)
    assert runner.invoke(app, [*render, "--overwrite"]).exit_code == 0


def test_replacing_a_data_set_keeps_what_the_tool_did_not_write(tmp_path):
    rng = np.random.default_rng(0)
    path = tmp_path / "d.zarr"
    write_dataset(path, [[1.0, 1.0]], [[0.0, 0.0]], rng.uniform(0.01, 0.1, (1, 8, 8, 3)), 0.25)
    (path / "notes.txt").write_text("my notes about this scan")
    with pytest.warns(UserWarning, match="kept 1 entries"):
        write_dataset(
            path, [[1.0, 1.0]], [[0.0, 0.0]], rng.uniform(0.01, 0.1, (1, 8, 8, 3)), 0.5, overwrite=True
        )
    assert (path / "notes.txt").read_text() == "my notes about this scan"
    assert (
        json.loads((path / "zarr.json").read_text())["attributes"]["translucency_dataset"]["pitch_mm"] == 0.5
    )
    with pytest.raises(TranslucencyError, match="not a translucency data set"):
        remove_dataset(tmp_path)


@pytest.mark.parametrize("kind", ["planar data set", "mesh data set", "model file", "output folder"])
def test_claim_refuses_the_root_home_and_parents(kind, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for path in ("/", "..", str(tmp_path)):
        with pytest.raises(TranslucencyError):
            claim_output(path, kind, overwrite=True)
