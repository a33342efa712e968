"""Checks before work, and what a run leaves (issue 22, section 3): every check that needs no work runs
before any estimate, progress bar or output; a failed run leaves nothing of its own behind; Ctrl-C says
what is kept and a resumed run says it resumes; estimates say when they are uncalibrated; the default
transport radius fits the memory; a model acquired from a user's filling renders its reference."""

import json
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import trimesh
import zarr
from typer.testing import CliRunner

from translucency import resources
from translucency._validate import TranslucencyError
from translucency.cli.app import app
from translucency.io.outputs import MARKER
from translucency.render.lights import DirectionalLight, PointLight
from translucency.render.object import check_light_outside
from translucency.resources import timing

runner = CliRunner()


def words(res) -> str:
    return " ".join(res.output.split())


@pytest.fixture(scope="module")
def ball(tmp_path_factory):
    """A ball of 642 vertices filled from a user's .npz, acquired (6 points) and fitted once."""
    root = tmp_path_factory.mktemp("ball")
    mesh = root / "ball.ply"
    trimesh.creation.icosphere(3, radius=6.0).export(mesh)
    filling = root / "filling.npz"
    shape = (13, 13, 13, 3)
    np.savez(filling, sigma_s=np.full(shape, 2.0), sigma_a=np.full(shape, 0.02), voxel_mm=1.0)
    data, model = root / "ball.zarr", root / "ball.model.zip"
    args = ["acquire", "mesh", "--mesh", mesh, "--volume", filling, "--points", "6", "--photons", "400"]
    res = runner.invoke(app, [*map(str, args), "--out", str(data), "--index-matched", "-q"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["fit", str(data), "--out", str(model), "-q"])
    assert res.exit_code == 0, res.output
    return {"mesh": mesh, "filling": filling, "data": data, "model": model, "root": root}


# -- checks before work ---------------------------------------------------------------------------------
def test_points_beyond_the_vertices_are_refused_before_any_estimate(ball, tmp_path):
    out = tmp_path / "b.zarr"
    res = runner.invoke(app, ["acquire", "mesh", "--mesh", str(ball["mesh"]), "--points", "1000000",
                              "--out", str(out)])  # fmt: skip
    assert res.exit_code == 2
    assert "--points: need 1 to 642" in words(res)
    assert "time about" not in res.output and "acquire" not in res.output.split("error")[0]
    assert not out.exists()


def test_up_is_checked_before_the_mesh_is_read(tmp_path):
    res = runner.invoke(app, ["acquire", "mesh", "--mesh", str(tmp_path / "absent.obj"), "--up", "w",
                              "--out", str(tmp_path / "b.zarr")])  # fmt: skip
    assert res.exit_code == 2
    assert "--up: expected one of z, y, x, got 'w'" in words(res)  # not "no such mesh file"


def test_a_light_inside_the_object_is_found_by_the_winding_number():
    ball = trimesh.creation.icosphere(3, radius=6.0)
    for light in (PointLight((0.0, 1.0, -2.0), 1.0), PointLight((5.5, 0.0, 0.0), 1.0)):
        with pytest.raises(TranslucencyError, match="inside the object"):
            check_light_outside(ball, light)
    check_light_outside(ball, PointLight((6.5, 0.0, 0.0), 1.0))
    check_light_outside(ball, DirectionalLight((0.0, 0.0, -1.0), 1.0))
    flipped = trimesh.Trimesh(
        ball.vertices, ball.faces[:, ::-1], process=False
    )  # orientation does not matter
    with pytest.raises(TranslucencyError, match="inside the object"):
        check_light_outside(flipped, PointLight((0.0, 0.0, 0.0), 1.0))


def test_render_refuses_a_light_inside_before_any_work(ball, tmp_path, monkeypatch):
    from translucency.workflow import rendering  # the module the command draws with (imported here, before
    # the patch: a module first imported while the still is patched would keep the stand-in for later tests)

    monkeypatch.setattr(rendering, "render_still", lambda *a, **k: pytest.fail("the transport ran"))
    out = tmp_path / "r"
    res = runner.invoke(app, ["render", str(ball["model"]), "--light", "point:0,0,1,10", "--out", str(out)])
    assert res.exit_code == 2
    assert "the point light at (0, 0, 1) mm is inside the object" in words(res)
    assert "time about" not in res.output and not out.exists()


def test_fit_refuses_an_unfinished_acquisition(ball, tmp_path):
    data = tmp_path / "unfinished.zarr"
    mesh, filling = str(ball["mesh"]), str(ball["filling"])
    res = runner.invoke(app, ["acquire", "mesh", "--mesh", mesh, "--volume", filling, "--points", "6",
                              "--photons", "400", "--chunk", "2", "--out", str(data), "-q"])  # fmt: skip
    assert res.exit_code == 0, res.output
    zarr.open_group(str(data), mode="r+")["chunk_done"][1] = False  # as an interrupted acquisition leaves it
    res = runner.invoke(app, ["fit", str(data), "--out", str(tmp_path / "m.model.zip")])
    assert res.exit_code == 2
    text = words(res)
    assert "unfinished acquisition (2/3 chunks done)" in text and "re-run the same" in text
    assert "None" not in text and not (tmp_path / "m.model.zip").exists()


# -- a failed run leaves nothing ------------------------------------------------------------------------
def _failing_still(prepared, light, out_dir, **kwargs):
    (out_dir / "ours.exr").write_bytes(b"half written")
    raise TranslucencyError("light: something went wrong half-way")


def test_a_failed_render_leaves_nothing_behind(ball, tmp_path, monkeypatch):
    from translucency.workflow import rendering as render_cli  # render_model imports render_still from here

    monkeypatch.setattr(render_cli, "render_still", _failing_still)
    new = tmp_path / "new"
    res = runner.invoke(app, ["render", str(ball["model"]), "--out", str(new), "--resolution", "32", "24"])
    assert res.exit_code == 2 and "half-way" in words(res)
    assert not new.exists()  # the folder it created is gone

    empty = tmp_path / "empty"
    empty.mkdir()
    res = runner.invoke(app, ["render", str(ball["model"]), "--out", str(empty), "--resolution", "32", "24"])
    assert res.exit_code == 2 and empty.is_dir() and not any(empty.iterdir())  # a folder there before stays

    old = tmp_path / "old"
    old.mkdir()
    (old / MARKER).write_text(json.dumps({"written_by": "translucency"}))
    (old / "figure2.png").write_bytes(b"an earlier render")
    args = ["render", str(ball["model"]), "--out", str(old), "--overwrite", "--resolution", "32", "24"]
    res = runner.invoke(app, args)
    assert res.exit_code == 2
    assert sorted(p.name for p in old.iterdir()) == sorted([MARKER, "figure2.png"])  # only its own removed
    assert (old / "figure2.png").read_bytes() == b"an earlier render"


# -- the default transport radius and the estimates --------------------------------------------------------
def test_the_default_radius_fits_a_share_of_the_memory_and_the_estimate_names_radius(ball, tmp_path):
    def radius(*extra):
        res = runner.invoke(app, ["render", str(ball["model"]), "--resolution", "32", "24", *extra])
        assert res.exit_code == 0, res.output
        text = words(res)
        assert "a smaller --radius lowers it" in text, text
        return float(re.search(r"transport radius ([0-9.e+-]+) mm", text).group(1))

    free = radius("--out", str(tmp_path / "a"))
    tight = radius("--out", str(tmp_path / "b"), "--max-memory", "300M")
    assert tight < 0.5 * free
    budget = resources.memory.transport_budget(300 * 2**20)
    V, area = 642, trimesh.creation.icosphere(3, radius=6.0).area
    assert (
        V**2 * np.pi * tight**2 / area <= budget * 1.01
    )  # within the budget (the radius printed to 3 digits)


def test_an_estimate_without_runs_of_its_size_says_it_is_uncalibrated():
    units = {"point_pixels": 1e6}
    first = timing.estimate_time("fit iso", units)
    assert "uncalibrated: first run here" in first.source
    base = timing._raw_seconds("fit iso", units)
    timing.record_time("fit iso", units, 2.0 * base)
    assert timing.estimate_time("fit iso", units).source == "calibrated on this machine by 1 earlier run"
    large = {"point_pixels": 1e9}  # 1000x the work: that run says little about it
    est = timing.estimate_time("fit iso", large)
    assert "uncalibrated: earlier runs here were of another size" in est.source


def test_a_stale_probe_of_an_older_version_is_not_used():
    path = timing.timing_file()
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({timing._machine(): {"probe_s": 1e-3, "runs": {"render": [0.01] * 5}}}))
    units = {"vertices": 1e4, "pairs": 1e7}
    est = timing.estimate_time("render", units)  # neither the old probe nor the size-less factors
    assert "uncalibrated" in est.source
    probe = json.loads(path.read_text())[timing._machine()][timing.PROBE_KEY]  # probed afresh
    raw = timing._raw_seconds("render", units)
    assert est.seconds == pytest.approx(raw * probe / timing.PROBE_REFERENCE_S)
    assert est.seconds != pytest.approx(raw * 1e-3 / timing.PROBE_REFERENCE_S)


# -- Ctrl-C and resuming ----------------------------------------------------------------------------------
def test_ctrl_c_says_what_is_kept_and_a_resumed_run_says_it_resumes(ball, tmp_path):
    out = tmp_path / "i.zarr"
    mesh, filling = str(ball["mesh"]), str(ball["filling"])
    args = [sys.executable, "-m", "translucency", "acquire", "mesh", "--mesh", mesh, "--volume", filling,
            "--points", "16", "--photons", "3000", "--chunk", "4", "--out", str(out)]  # fmt: skip
    env = {**os.environ, "COLUMNS": "200"}
    proc = subprocess.Popen(args, stderr=subprocess.PIPE, text=True, env=env)
    flag = out / "chunk_done" / "c" / "0"
    t = time.monotonic()
    while proc.poll() is None and not flag.exists() and time.monotonic() - t < 300:
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=300)
    if proc.returncode == 0:
        pytest.skip("the acquisition finished before the interrupt arrived")
    assert proc.returncode == 130, err
    note = re.search(r"interrupted: (\d)/4 chunks kept in .*; re-run the same command to resume", err)
    assert note, err
    assert "Traceback" not in err and not (tmp_path / ".i.zarr.lock").exists()
    kept = int(note.group(1))
    res = subprocess.run(args, capture_output=True, text=True, env=env)
    assert res.returncode == 0, res.stderr
    text = " ".join(res.stderr.split())
    assert f"resuming ({kept}/4 chunks done, kept): the {16 - 4 * kept} incident points" in text, text


@pytest.mark.parametrize("where", ["inside a traced loop", "inside a library that drops the cause"])
def test_ctrl_c_at_any_moment_ends_in_the_kept_line(ball, tmp_path, monkeypatch, where):
    """The interrupt placed, not timed: it lands while Dr.Jit traces the walk's loop body of the second
    chunk (Dr.Jit re-raises it as a RuntimeError caused by it), or in a library that catches it and raises
    an error of its own with no cause (a real SIGINT, noted by the command's handler as it arrives)."""
    from translucency.acquire import mesh as scan
    from translucency.acquire import mesh_walk

    walks = {"n": 0, "armed": False}
    walk, medium_event = scan.mesh_random_walk, mesh_walk._medium_event

    def counted_walk(*args, **kwargs):
        walks["n"] += 1
        walks["armed"] = walks["n"] == 4  # one walk a channel: the second chunk's first
        return walk(*args, **kwargs)

    def interrupted_once(*args, **kwargs):
        if walks["armed"]:
            walks["armed"] = False
            if where == "inside a traced loop":
                raise KeyboardInterrupt
            try:
                signal.raise_signal(signal.SIGINT)
            except KeyboardInterrupt:
                raise RuntimeError("a library's own error") from None
        return medium_event(*args, **kwargs)

    monkeypatch.setattr(scan, "mesh_random_walk", counted_walk)
    monkeypatch.setattr(mesh_walk, "_medium_event", interrupted_once)
    # Python's own handler, as a user's terminal gives it (a suite started in the background by a shell
    # inherits SIGINT ignored, where no Ctrl-C arrives at all); set back after the command
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    out = tmp_path / "i.zarr"
    args = ["acquire", "mesh", "--mesh", str(ball["mesh"]), "--volume", str(ball["filling"]), "--points", "8",
            "--photons", "50", "--chunk", "4", "--out", str(out)]  # fmt: skip
    try:
        res = runner.invoke(app, args)
    finally:
        now = signal.signal(signal.SIGINT, previous)
    assert now is signal.default_int_handler  # the command's handler is gone
    assert walks["n"] == 4, "the interrupt did not land in the second chunk's walk"
    assert res.exit_code == 130, res.output
    assert "interrupted: 1/2 chunks kept in" in words(res)
    assert "re-run the same command to resume" in words(res)
    assert "Traceback" not in res.output and not (tmp_path / ".i.zarr.lock").exists()


# -- the reference of a user's filling ---------------------------------------------------------------------
def test_the_reference_of_a_users_filling_renders_while_the_file_is_unchanged(ball, tmp_path):
    header = zarr.open_group(str(ball["data"]), mode="r").attrs["translucency_mesh_dataset"]
    assert header["filling"]["path"] == str(ball["filling"].resolve())
    assert len(header["filling"]["sha256"]) == 64
    args = ["render", str(ball["model"]), "--reference", "--resolution", "24", "18", "--reference-spp", "2"]
    args += ["-q"]
    res = runner.invoke(app, [*args, "--out", str(tmp_path / "r")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "r" / "reference.exr").is_file()

    copy = tmp_path / "filling.npz"
    copy.write_bytes(ball["filling"].read_bytes())
    with np.load(copy) as f:
        arrays = {k: f[k] for k in f.files}
    arrays["sigma_s"] = arrays["sigma_s"] * 2
    np.savez(ball["filling"], **arrays)
    try:
        res = runner.invoke(app, [*args, "--out", str(tmp_path / "changed")])
        assert res.exit_code == 2 and "the filling changed since this object was acquired" in words(res)
        assert not (tmp_path / "changed").exists()
        ball["filling"].unlink()
        res = runner.invoke(app, [*args, "--out", str(tmp_path / "gone")])
        assert res.exit_code == 2 and "the filling this object was acquired from is gone" in words(res)
    finally:
        ball["filling"].write_bytes(copy.read_bytes())


def test_a_reference_volpath_cannot_light_is_refused_before_any_work(ball, tmp_path, monkeypatch):
    from translucency.workflow import rendering  # the module the command draws with (imported here, before
    # the patch: a module first imported while the still is patched would keep the stand-in for later tests)

    monkeypatch.setattr(rendering, "render_still", lambda *a, **k: pytest.fail("the transport ran"))
    dielectric = tmp_path / "d.zarr"  # the same ball behind a dielectric boundary (not index-matched)
    args = ["acquire", "mesh", "--mesh", str(ball["mesh"]), "--volume", str(ball["filling"]), "--points", "2"]
    res = runner.invoke(app, [*args, "--photons", "200", "--out", str(dielectric), "-q"])
    assert res.exit_code == 0, res.output
    model = tmp_path / "d.model.zip"
    assert runner.invoke(app, ["fit", str(dielectric), "--out", str(model), "-q"]).exit_code == 0
    out = tmp_path / "r"
    res = runner.invoke(app, ["render", str(model), "--reference", "--out", str(out)])
    assert res.exit_code == 2 and "volpath cannot light a dielectric object" in words(res)
    assert "time about" not in res.output and not out.exists()


# -- evaluate's report ------------------------------------------------------------------------------------
def test_evaluate_writes_its_report_beside_the_model_unless_asked(tmp_path, monkeypatch):
    slab = ["--material", "homogeneous:marble", "--size", "10", "10", "4", "--voxel", "0.5"]
    data = tmp_path / "m.zarr"
    res = runner.invoke(
        app, ["acquire", "planar", *slab, "--grid", "2", "--photons", "500", "--out", str(data)]
    )
    assert res.exit_code == 0, res.output
    for name in ("iso", "dipole"):
        res = runner.invoke(app, ["fit", str(data), "--model", name, "--out", f"{name}.model.zip", "-q"])
        assert res.exit_code == 0, res.output
    for name in ("iso", "dipole"):  # two models of the same data, in the same folder
        res = runner.invoke(app, ["evaluate", f"{name}.model.zip", str(data), "-q"])
        assert res.exit_code == 0, res.output
        assert (tmp_path / f"{name}.report" / "index.html").is_file()
    assert not (tmp_path / "report").exists()

    from translucency.evaluate import report as evaluate_cli  # the command imports write_report from here

    def failing(models, ds, report, **kwargs):
        (report / "figure1.png").write_bytes(b"half written")
        raise TranslucencyError("data: something went wrong half-way")

    monkeypatch.setattr(evaluate_cli, "write_report", failing)
    res = runner.invoke(app, ["evaluate", "iso.model.zip", str(data), "--report", "new"])
    assert res.exit_code == 2 and not (tmp_path / "new").exists()  # a failed evaluate leaves nothing


def test_a_first_run_with_cold_kernel_caches_adds_its_compiling(tmp_path, monkeypatch):
    units = {"vertices": 1e3, "pairs": 1e5}
    warm = timing.estimate_time("render", units)
    cold = timing.estimate_time("render", units, cold=True)
    first = timing.TIME_TERMS["render"]["first_run"]
    assert cold.seconds == pytest.approx(warm.seconds * (1 + first / timing._raw_seconds("render", units)))
    assert "compiling kernels on a first run" in cold.source and "compiling" not in warm.source
    timing.record_time("render", units, 3 * (timing._raw_seconds("render", units) + first), cold=True)
    assert timing.estimate_time("render", units).seconds == pytest.approx(
        3 * timing._raw_seconds("render", units)
    )
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))  # an empty Numba cache: cold
    (tmp_path / "numba").mkdir()
    assert timing.kernel_caches_cold()
    (tmp_path / "numba" / "transport.f-448.nbi").write_bytes(b"")
    monkeypatch.setenv("HOME", str(tmp_path))
    (tmp_path / ".drjit").mkdir()
    assert timing.kernel_caches_cold()  # Dr.Jit's cache is empty
    (tmp_path / ".drjit" / "k.llvm.v6.bin").write_bytes(b"")
    assert not timing.kernel_caches_cold()


def test_the_estimate_states_the_seconds_already_spent():
    est = timing.TimeEstimate(10.0, "calibrated on this machine by 2 earlier runs", startup=5.0)
    assert est.text() == "about 15 s in all (5 s of it so far; calibrated on this machine by 2 earlier runs)"
    assert est.as_dict()["startup_seconds"] == 5.0 and est.as_dict()["seconds"] == 10.0
    assert timing.process_seconds() > 0
