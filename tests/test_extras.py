"""The extras (translucency/_extras.py, pyproject's optional dependencies): without any of them the package
imports, every command's ``--help`` works and the core runs; a command that needs a missing one ends with
one line, exit status 2, naming the command and the pip install; where an extra is optional in a job (FLIP)
the job goes on and says what it skipped.

Each check runs in a fresh interpreter with the extras' modules blocked (``sys.modules[name] = None``: an
``import`` of them raises ImportError, as where they are not installed).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import trimesh

from translucency._extras import EXTRAS, MissingExtra, install_line, require, skipped

ROOT = Path(__file__).resolve().parents[1]

#: the modules each extra brings, blocked to play its absence
BLOCKED = {
    "rig": ("cv2",),
    "cluster": ("dask", "distributed"),
    "viewer": ("fast_simplification",),
    "flip": ("flip_evaluator",),
}
ALL = tuple(m for names in BLOCKED.values() for m in names)

_PRELUDE = """
import sys
for name in {blocked!r}:
    sys.modules[name] = None
"""

_CLI = """
sys.argv = ["translucency", *{args!r}]
from translucency.cli.app import main
main()
"""


def _python(body: str, blocked=ALL, timeout: float = 600) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONSTARTUP", "COLUMNS")}
    env["COLUMNS"] = "400"  # one line is one line
    return subprocess.run(
        [sys.executable, "-c", _PRELUDE.format(blocked=tuple(blocked)) + body],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        cwd=ROOT,
    )


def _cli(args, blocked=ALL, timeout: float = 600) -> subprocess.CompletedProcess:
    return _python(_CLI.format(args=[str(a) for a in args]), blocked, timeout)


def _the_line(res: subprocess.CompletedProcess, command: str, extra: str) -> None:
    """The command ended with exactly the one line naming it and the extra's install, exit status 2."""
    errors = [ln for ln in res.stderr.splitlines() if ln.startswith("error:")]
    assert res.returncode == 2, res.stderr[-2000:]
    assert "Traceback" not in res.stderr, res.stderr[-2000:]
    assert len(errors) == 1, res.stderr[-2000:]
    assert errors[0].startswith(f"error: translucency {command}"), errors[0]
    assert errors[0].endswith(f'needs the {extra} extra: pip install "translucency[{extra}]"'), errors[0]


# ---------------------------------------------------------------------------------------------------------
# pyproject's extras are the ones the package knows


def test_the_extras_of_pyproject_are_the_packages_own():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]
    core = " ".join(project["dependencies"])
    for extra, (package, _, _) in EXTRAS.items():
        assert any(dep.startswith(package) for dep in extras[extra]), (extra, extras[extra])
        assert package.split("[")[0] not in core, f"{package} is still a core dependency"
    assert extras["all"] == [f"translucency[{','.join(EXTRAS)}]"]
    assert "translucency[all]" in extras["test"]  # make test has every extra


def test_the_messages():
    assert install_line("viewer") == 'pip install "translucency[viewer]"'
    line = 'FLIP skipped: it needs the flip extra: pip install "translucency[flip]"'
    assert skipped("flip", "FLIP") == line
    with pytest.raises(ValueError, match="no extra 'gpu'"):
        install_line("gpu")
    assert require("flip").__name__ == "flip_evaluator"  # installed here (the test extra pulls all)


def test_the_command_line_prints_the_install_line_as_text(capsys):
    """An information line from the library goes through Rich: its ``[flip]`` is text, not markup."""
    from translucency.cli._run import RichReporter

    RichReporter(quiet=False).info(skipped("flip", "FLIP"))
    said = " ".join(capsys.readouterr().err.split())
    assert said == 'FLIP skipped: it needs the flip extra: pip install "translucency[flip]"'


def test_a_missing_extra_from_python_names_the_feature():
    res = _python(
        "from translucency._extras import require, MissingExtra\n"
        "try:\n    require('viewer')\nexcept MissingExtra as exc:\n    print(exc.extra, '|', exc)\n"
        "from translucency.cluster import parse_scheduler\n"
        "try:\n    parse_scheduler('local:2')\nexcept MissingExtra as exc:\n    print(exc)\n"
        "print(parse_scheduler('threads'))\n"
    )
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.splitlines() == [
        'viewer | the viewer\'s reduced mesh needs the viewer extra: pip install "translucency[viewer]"',
        "scheduler='local:2' needs the cluster extra: pip install \"translucency[cluster]\"",
        "threads",  # this process's threads need no Dask
    ]
    assert issubclass(MissingExtra, Exception)


# ---------------------------------------------------------------------------------------------------------
# the core without any extra

_EVERY_HELP = """
import typer.main
from typer.testing import CliRunner
import translucency
from translucency.cli.app import app


def commands(group, path=()):
    yield list(path)
    for name, sub in getattr(group, "commands", {}).items():
        yield from commands(sub, (*path, name))


failed, seen = [], []
for args in commands(typer.main.get_command(app)):
    seen.append(" ".join(args))
    if CliRunner().invoke(app, [*args, "--help"]).exit_code != 0:
        failed.append(" ".join(args))
print(json.dumps({"failed": failed, "seen": seen, "version": translucency.__version__}))
"""


def test_import_and_every_help_without_the_extras():
    res = _python("import json\n" + _EVERY_HELP)
    assert res.returncode == 0, res.stderr[-2000:]
    out = json.loads(res.stdout.strip().splitlines()[-1])
    assert out["failed"] == [] and {"view", "import images", "acquire mesh", "examples"} <= set(out["seen"])


def test_the_core_acquires_and_fits_without_the_extras(tmp_path):
    """acquire planar and fit in this process's threads, with every extra blocked."""
    data, model = tmp_path / "a.zarr", tmp_path / "a.model.zip"
    acquire = ["acquire", "planar", "--material", "marble", "--grid", "2", "--span", "2", "--photons", "300"]
    acquire += ["--size", "6", "6", "3", "--voxel", "0.5", "--window", "2", "--pitch", "0.5", "-q"]
    res = _cli([*acquire, "--out", data])
    assert res.returncode == 0, res.stderr[-2000:]
    res = _cli(["fit", data, "--out", model, "--rounds", "1", "-q"])
    assert res.returncode == 0, res.stderr[-2000:]
    assert model.is_file()


# ---------------------------------------------------------------------------------------------------------
# each extra: the command that needs it, one line


@pytest.mark.parametrize(
    "command",
    [
        ["acquire", "planar", "--material", "marble", "--scheduler", "local:2"],
        ["fit", "DATA", "--scheduler", "tcp://127.0.0.1:8786"],
    ],
    ids=["acquire planar", "fit"],
)
def test_a_cluster_scheduler_needs_the_cluster_extra(tmp_path, command):
    args = [str(tmp_path / "d.zarr") if a == "DATA" else a for a in command]
    res = _cli([*args, "--out", tmp_path / "out"], blocked=BLOCKED["cluster"])
    _the_line(res, " ".join(command[:2]) if command[0] == "acquire" else "fit", "cluster")
    assert f"with --scheduler {command[-1]} needs" in res.stderr
    assert not (tmp_path / "out").exists()  # said before any work


@pytest.mark.parametrize(
    "command",
    [
        ["acquire", "photographs", "--material", "marble", "--grid", "1", "--span", "1"],
        ["acquire", "object-photographs"],
        ["import", "object", "RIG"],
    ],
    ids=["acquire photographs", "acquire object-photographs", "import object"],
)
def test_the_rig_commands_need_the_rig_extra(tmp_path, command):
    args = [str(tmp_path / "object.json") if a == "RIG" else a for a in command]
    res = _cli([*args, "--out", tmp_path / "out"], blocked=BLOCKED["rig"])
    _the_line(res, " ".join(command[:2]), "rig")
    assert not (tmp_path / "out").exists()


def test_import_images_with_marked_points_needs_the_rig_extra(tmp_path):
    """A calibration from marked points is OpenCV's homography: the rig extra."""
    square = [[0, 0], [4, 0], [4, 4], [0, 4]]
    spec = {"points": {"sample_mm": square, "image_px": [[10 * x + 5, 10 * y + 7] for x, y in square]}}
    (tmp_path / "cal.json").write_text(json.dumps({**spec, "scale": 2.5}))
    (tmp_path / "shots").mkdir()
    (tmp_path / "pos.csv").write_text("file,x,y\na.pfm,3.2,3.2\n")
    args = ["import", "images", tmp_path / "shots", "-p", tmp_path / "pos.csv", "-c", tmp_path / "cal.json"]
    res = _cli([*args, "--out", tmp_path / "out.zarr"], blocked=BLOCKED["rig"])
    _the_line(res, "import images", "rig")


def test_view_of_a_large_mesh_needs_the_viewer_extra(tmp_path):
    """A mesh beyond the reduced mesh's triangles (fast-simplification draws it while the light moves)."""
    from helpers import random_exponential_model
    from translucency import save_model
    from translucency.view.surface import REDUCED_FACES

    ball = trimesh.creation.icosphere(5, radius=20.0)
    assert len(ball.faces) > REDUCED_FACES
    model = random_exponential_model(
        np.random.default_rng(0), geometry="mesh", mesh=ball, points=np.arange(0, len(ball.vertices), 997)
    )
    model.faces = np.asarray(ball.faces)
    path = save_model(model, tmp_path / "ball.model.zip")
    res = _cli(["view", path, "--export", tmp_path / "page"], blocked=BLOCKED["viewer"])
    _the_line(res, "view", "viewer")
    assert not (tmp_path / "page").exists()


def test_without_flip_a_comparison_keeps_its_rmse():
    """compare() without the flip extra: the relative RMSE, no FLIP entries, no map; the line to say so."""
    res = _python(
        "import json, numpy as np\n"
        "from translucency.render.compare import FLIP_SKIPPED, compare, flip_available\n"
        "ref = np.full((8, 8, 3), 0.2)\n"
        "mask = np.zeros((8, 8), bool)\n"
        "mask[2:6, 2:6] = True\n"
        "out = compare(ref, 1.5 * ref, mask)\n"
        "print(json.dumps({'keys': sorted(out), 'rmse': out['rel_rmse'], 'map': out['flip_map'] is None,"
        " 'available': flip_available(), 'line': FLIP_SKIPPED}))\n",
        blocked=BLOCKED["flip"],
    )
    assert res.returncode == 0, res.stderr[-2000:]
    out = json.loads(res.stdout.strip().splitlines()[-1])
    assert out["keys"] == ["exposure", "flip_map", "rel_rmse"] and out["map"] and not out["available"]
    assert abs(out["rmse"] - 0.5) < 1e-12  # 50 % too bright everywhere on the object
    assert out["line"].endswith('needs the flip extra: pip install "translucency[flip]"')


@pytest.mark.slow
def test_the_main_job_runs_without_the_extras(tmp_path):
    """``translucency demo`` with every extra blocked: the whole main job, FLIP said to be skipped once."""
    res = _cli(["demo", "--out", tmp_path / "results"], timeout=3600)
    assert res.returncode == 0, res.stderr[-3000:]
    said = " ".join(res.stderr.split())  # Rich wraps long lines at the terminal's width
    assert said.count('needs the flip extra: pip install "translucency[flip]"') == 1, res.stderr[-3000:]
    report = (tmp_path / "results" / "report" / "index.html").read_text()
    assert "FLIP not measured (the flip extra)" in report
    figure2 = json.loads((tmp_path / "results" / "report" / "figure2.json").read_text())
    assert np.isfinite(figure2["rel_rmse"]) and "flip_mean_object" not in figure2
