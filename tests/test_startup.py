"""Start-up: ``translucency --help`` and ``info`` load only what they use.

Not a timing test (machines differ): each check runs in a fresh interpreter and lists the heavy packages
that ended up in ``sys.modules``.  ``--help`` is built from the commands' signatures, so the command
modules must import their stages (Mitsuba, Dask, Matplotlib, Numba, SciPy's optimisers, trimesh,
scikit-image) inside the commands, and the stores their Zarr where they are opened; ``info`` reads a
file with Zarr and NumPy and needs no engine.
``benchmarks/startup.py`` measures the times.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

#: what neither the package, nor the command tree, nor any command's --help may load
NOT_FOR_HELP = (
    "mitsuba",
    "drjit",
    "dask",
    "distributed",
    "matplotlib",
    "numba",
    "scipy.optimize",
    "skimage",
    "trimesh",
    "zarr",
)
#: what ``info`` on a model file or a data set may not load
NOT_FOR_INFO = ("mitsuba", "drjit", "dask", "distributed", "matplotlib")

_PROBE = """
import json, sys
{body}
loaded = [m for m in {heavy!r} if m in sys.modules]
print(json.dumps({{"loaded": loaded, "code": code, "detail": globals().get("detail")}}))
"""

_RUN_CLI = """
from typer.testing import CliRunner
from translucency.cli.app import app
code = CliRunner().invoke(app, {args!r}).exit_code
"""


def _loaded(body: str, heavy) -> dict:
    """Run ``body`` in a fresh interpreter: the heavy modules it left in ``sys.modules``, its ``code`` (and
    its ``detail``, if it sets one)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONSTARTUP"}
    res = subprocess.run(
        [sys.executable, "-c", _PROBE.format(body=body, heavy=tuple(heavy))],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    assert res.returncode == 0, res.stderr[-2000:]
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_import_translucency_loads_no_engine():
    out = _loaded("import translucency\ncode = 0", (*NOT_FOR_HELP, "scipy"))
    assert out["loaded"] == []


def test_the_command_tree_loads_no_engine():
    out = _loaded("import translucency.cli.app\ncode = 0", NOT_FOR_HELP)
    assert out["loaded"] == []


_EVERY_HELP = """
import typer.main
from typer.testing import CliRunner
from translucency.cli.app import app


def commands(group, path=()):
    yield list(path)
    for name, sub in getattr(group, "commands", {{}}).items():
        yield from commands(sub, (*path, name))


code, first, seen = 0, {{}}, []
for args in commands(typer.main.get_command(app)):  # every command and group, as --help lists them
    seen.append(" ".join(args))
    code = max(code, CliRunner().invoke(app, [*args, "--help"]).exit_code)
    for m in {heavy!r}:
        if m in sys.modules:
            first.setdefault(m, " ".join(args) or "top")
detail = {{"first loaded by": first, "commands": seen}}
"""


def test_every_help_loads_no_engine():
    out = _loaded(_EVERY_HELP.format(heavy=NOT_FOR_HELP), NOT_FOR_HELP)
    assert out["code"] == 0
    assert {"fit", "info", "acquire mesh", "import images"} <= set(out["detail"]["commands"])
    assert out["loaded"] == [], f"--help loaded {out['detail']['first loaded by']}"


@pytest.fixture
def small_model_file(tmp_path):
    from translucency import ExponentialModel, PlanarAlpha, save_model

    alpha = PlanarAlpha.uniform((8, 8), pitch=0.5)
    model = ExponentialModel(
        np.zeros((1, 2)), [[[[0.05]]]], [[[[-1.0]]]], alpha, s_g=[1.0], s_b=[1.0]
    )  # one point, one term: R_d = 0.05 e^{-r} mm⁻²
    return save_model(model, tmp_path / "small.model.zip")


def test_info_on_a_model_file_loads_no_engine(small_model_file):
    out = _loaded(_RUN_CLI.format(args=["info", str(small_model_file)]), NOT_FOR_INFO)
    assert out["code"] in (0, 1)  # valid or not: the file was read and described
    assert out["loaded"] == []


def test_info_on_a_data_set_loads_no_engine():
    from translucency.data import default_dataset_path

    out = _loaded(_RUN_CLI.format(args=["info", str(default_dataset_path())]), NOT_FOR_INFO)
    assert out["code"] == 0
    assert out["loaded"] == []


def test_the_lazy_names_of_the_package_are_its_own():
    import translucency as tl
    from translucency.io.model_file import load_model
    from translucency.model import MATERIALS, ExponentialModel

    assert tl.load_model is load_model and tl.ExponentialModel is ExponentialModel
    assert tl.MATERIALS is MATERIALS and tl.data.default_dataset_path().exists()
    assert {"load_model", "data", "fit_model"} <= set(dir(tl))
    with pytest.raises(AttributeError):
        tl.no_such_name  # noqa: B018
