"""The function-first API (``translucency.fit`` …): the README's session, light import, errors that name
Python arguments while the command line names its flags."""

import json
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import translucency as tl
from translucency.cli._flags import FLAGS, cli_words
from translucency.cli.app import app

README = Path(__file__).resolve().parents[1] / "README.md"
runner = CliRunner()


def readme_session() -> str:
    """The first Python block of the README's "Python" section."""
    section = README.read_text().split("## Python\n", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_readme_session_prints_the_held_out_error_of_translucency_evaluate(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    session = readme_session()
    assert len(session.strip().splitlines()) <= 10
    namespace = {}
    exec(compile(session, "README.md", "exec"), namespace)
    printed = capsys.readouterr().out.strip().splitlines()[-1]
    assert printed == f"held-out error: {100 * namespace['errors'].rel_l2:.2f} %"
    # the same model (the file the session wrote) and truth through the command line
    model = tmp_path / "marble_iso.model.zip"
    truth = tl.data.default_truth_path()
    args = ["evaluate", str(model), str(tl.data.default_dataset_path()), "--truth", str(truth)]
    res = runner.invoke(app, [*args, "--report", str(tmp_path / "report"), "--json"])
    assert res.exit_code == 0, res.output
    cli = json.loads(res.stdout[res.stdout.index("{") :])
    assert cli["evaluated_against"].startswith("truth")
    assert printed == f"held-out error: {100 * cli['rel_l2']:.2f} %"
    # and the API gives the command's numbers exactly on that file
    again = tl.evaluate_model(model, tl.data.default_dataset(), truth=truth)
    assert again.rel_l2 == cli["rel_l2"]
    assert again.bands["near"] == cli["rel_l2_near"] and again.bands["far"] == cli["rel_l2_far"]
    assert abs(again.rel_l2 - namespace["errors"].rel_l2) < 1e-5  # float32 storage of the parameters


def test_import_is_light_and_keeps_the_engine_private():
    code = (
        "import os, sys, translucency as tl; "
        "heavy = ('mitsuba', 'drjit', 'dask', 'distributed', 'matplotlib'); "
        "print(sorted(m for m in heavy if m in sys.modules)); "
        "print(hasattr(tl, 'prepare_libllvm'), 'DRJIT_LIBLLVM_PATH' in os.environ)"
    )
    env = {**os.environ}
    env.pop("DRJIT_LIBLLVM_PATH", None)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    heavy, flags = out.stdout.strip().splitlines()
    assert heavy == "[]"
    assert flags.split()[0] == "False"
    from importlib.metadata import PackageNotFoundError, distribution

    try:
        distribution("karellen-llvm-core")
    except PackageNotFoundError:
        return
    assert flags.split()[1] == "True"  # Dr.Jit's libLLVM is still chosen when translucency is imported


def test_functions_and_stages_have_names_of_their_own():
    import translucency.evaluate.errors  # noqa: F401 — the stages, imported after the functions
    import translucency.fit.planar  # noqa: F401
    import translucency.render.still  # noqa: F401
    import translucency.transport  # noqa: F401

    functions = ("fit_model", "evaluate_model", "render_model", "render_scene", "open_dataset")
    for name in (*functions, "acquire_planar", "acquire_mesh", "import_images"):
        assert callable(getattr(tl, name)) and getattr(tl, name).__module__.startswith(
            "translucency.workflow."
        )
        assert getattr(tl, name).__doc__ and "Examples" in getattr(tl, name).__doc__
    # a stage is its package, a function is a verb with its object: importing one never hides the other
    for stage in ("fit", "evaluate", "transport", "render"):
        assert isinstance(getattr(tl, stage), types.ModuleType)
        assert getattr(tl, stage) is sys.modules[f"translucency.{stage}"]
    assert set(functions) <= set(dir(tl)) and set(functions) <= set(tl.__all__)
    assert not {"fit", "evaluate", "transport", "render"} & set(tl.__all__)
    assert not {"prepare_libllvm", "sys", "types"} & set(dir(tl))


def test_open_dataset_opens_either_kind(tmp_path):
    planar = tl.open_dataset(tl.data.default_dataset_path())
    assert type(planar).__name__ == "PlanarDataset" and planar.n_points == 1024
    with pytest.raises(tl.TranslucencyError, match="^path: expected a path, got int$"):
        tl.open_dataset(3)


def test_library_errors_name_python_arguments(tmp_path):
    model = tl.ExponentialModel(
        [[0.0, 0.0]], [[[[1.0]]]], [[[[-2.0]]]], tl.PlanarAlpha.uniform((2, 2)), s_g=[1.0], s_b=[1.0]
    )
    path = tl.save_model(model, tmp_path / "m.model.zip")
    with pytest.raises(tl.TranslucencyError) as exc:
        tl.save_model(model, path)
    assert "overwrite=True" in str(exc.value) and "--" not in str(exc.value)
    assert cli_words(str(exc.value)).startswith(f"--out {path}: ")
    assert "pass --overwrite to replace it" in cli_words(str(exc.value))
    data = tl.data.default_dataset()
    for call, message in [
        (lambda: tl.fit_model(data, n_terms="three"), "n_terms: expected a whole number or 'auto'"),
        (lambda: tl.fit_model(data, max_rounds=0), "max_rounds: must be >= 1, got 0"),
        (lambda: tl.fit_model(data, rounds=2), "rounds: not an option of fit on a planar data set"),
        (lambda: tl.fit_model(data, exclusion_mm=float("nan")), "exclusion_mm: must be a finite number"),
        (lambda: tl.evaluate_model(model, data, truth=5), "truth: expected a planar data set"),
        (lambda: tl.render_model(model, resolution=(0, 10)), "resolution: must be >= 1, got 0"),
        (lambda: tl.render_model(model), "model: a planar model; render needs a per-vertex model"),
        (lambda: tl.acquire_planar("no-such.npz", tmp_path / "d.zarr"), "no-such.npz"),
        (lambda: tl.acquire_planar(object(), tmp_path / "d.zarr"), "sample: expected a Volume"),
        (lambda: tl.import_images(tmp_path, "p.csv", None, tmp_path / "o.zarr", pitchh=1), "pitchh: not a"),
    ]:
        with pytest.raises(tl.TranslucencyError) as exc:
            call()
        text = str(exc.value)
        assert message in text and "\n" not in text, text


def test_cli_words_translate_only_arguments():
    assert FLAGS["overwrite"] == "--overwrite" and FLAGS["n_terms"] == "--terms"
    assert cli_words("n_terms: must be between 1 and 4") == "--terms: must be between 1 and 4"
    assert (
        cli_words("out x.zarr: pass overwrite=True to replace it")
        == "--out x.zarr: pass --overwrite to replace it"
    )
    assert cli_words("a.ply: at scale_mm=0.001 mm per unit; scale_mm=1 if it is in mm") == (
        "a.ply: at --scale 0.001 mm per unit; --scale 1 if it is in mm"
    )
    # words that are not arguments, header fields, flags and paths stay as they are
    for text in (
        "--out /data/out_dir.zarr: the output stays out of it",
        "model: expected one of iso, aniso",
        "x.zarr: header fields n_points 3, chunk_points 4",
        "/tmp/overwrite=True/x: y",
    ):
        assert cli_words(text) == text


def test_fit_dispatches_on_the_data_set(tmp_path):
    rng = np.random.default_rng(0)
    from translucency.io.dataset import write_dataset

    ds = write_dataset(
        tmp_path / "d.zarr", [[2.0, 2.0]], [[0.0, 0.0]], rng.uniform(0.01, 0.1, (1, 16, 16, 3)), 0.25
    )
    result = tl.fit_model(ds.path, max_rounds=1)
    assert result.model.geometry == "planar" and result.model.n_points == 1
    errors = tl.evaluate_model(result, ds)
    assert np.isfinite(errors.rel_l2) and errors.rel_l2 == tl.evaluate_model(result.model, ds.path).rel_l2


def test_acquire_fit_and_render_an_object(tmp_path):
    import trimesh

    ball = trimesh.creation.icosphere(2, radius=4.0)
    ds = tl.acquire_mesh(
        ball,
        tmp_path / "ball.zarr",
        "homogeneous:marble",
        voxel_mm=1.0,
        points=4,
        photons=300,
        index_matched=True,
    )
    assert type(ds).__name__ == "MeshDataset" and ds.n_points == 4
    assert type(tl.open_dataset(ds.path)).__name__ == "MeshDataset"
    result = tl.fit_model(ds, max_rounds=1)
    assert result.model.geometry == "mesh" and result.model.n_points == 4
    shown = tl.render_model(result, resolution=(16, 12))
    assert shown.picture.shape == (12, 16, 3) and np.isfinite(shown.picture).all() and shown.picture.max() > 0
    assert (
        shown.folder is None and shown.reference is None and shown.numbers["vertices"] == len(ball.vertices)
    )
    kept = tl.render_model(result, tmp_path / "r", resolution=(16, 12))
    assert kept.folder == tmp_path / "r" and (tmp_path / "r" / "ours.exr").is_file()
    np.testing.assert_array_equal(kept.picture, shown.picture)
    with pytest.raises(tl.TranslucencyError, match="pass overwrite=True"):
        tl.render_model(result, tmp_path / "r", resolution=(16, 12))
    errors = tl.evaluate_model(result, ds)  # per-vertex errors (tests/test_evaluate_mesh.py)
    assert type(errors).__name__ == "MeshErrors" and np.isfinite(errors.rel_l2)


def test_acquire_planar_then_fit(tmp_path):
    slab = tl.make_sample("marble", (6.0, 6.0, 2.0), 1.0)
    with pytest.raises(tl.TranslucencyError, match="^grid: must be >= 1, got 0$"):
        tl.acquire_planar(slab, tmp_path / "d.zarr", grid=0)
    ds = tl.acquire_planar(slab, tmp_path / "d.zarr", grid=1, span=0.0, window=2.0, photons=100)
    assert ds.n_points == 1 and ds.window == (9, 9) and ds.header["acquisition"]["photons"] == 100
    with pytest.raises(tl.TranslucencyError, match="pass overwrite=True"):
        tl.acquire_planar(slab, tmp_path / "d.zarr", grid=1, span=0.0, window=2.0, photons=200)
    assert tl.fit_model(tmp_path / "d.zarr", max_rounds=1).model.n_points == 1
