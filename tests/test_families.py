"""A model family is one module and one registration line (docs/architecture.md, "How to add a model
family"): a family written in a module of its own — here in a temporary folder, outside the package —
and registered with :func:`translucency.fit.families.register` is a ``fit --model`` choice of the
CLI and of the API, is timed and sized by the estimates, and writes a model file that loads."""

from __future__ import annotations

import importlib.util
import textwrap

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from translucency.cli.app import app
from translucency.fit import FAMILIES, fit_planar
from translucency.fit.families import describe_families, register
from translucency.io.dataset import write_dataset
from translucency.io.model_file import load_model
from translucency.model import ExponentialModel, PlanarAlpha

PITCH = 0.25

#: a seventh family: the isotropic fit without its energy guard (a variant a researcher might try)
FAMILY_MODULE = '''
import numpy as np

from translucency.fit.families.iso import IsoFamily
from translucency.fit._pixels import grouped
from translucency.fit.families._exponential import solve_exponentials


class UnguardedIsoFamily(IsoFamily):
    """The paper's isotropic sum of exponentials, fitted without the energy guard."""

    name = "iso-unguarded"
    time_terms = {"overhead": 0.3, "point_pixels": 1.0e-6}

    def fit_profiles(self, ctx, state, sl, ch, w2):
        k, C, G = ch.y.shape[0], ctx.C, ch.r_g.size
        kappa = ch.alpha * state.s[sl][:, None, :].astype(np.float32) if C == 1 else ch.alpha
        W, Y = grouped(ch.rings, G, C, w2, kappa, ch.y)
        solve_exponentials(ctx, state, sl, ch, W, Y, np.arange(k * C))
'''


@pytest.fixture
def seventh_family(tmp_path):
    path = tmp_path / "my_family.py"
    path.write_text(textwrap.dedent(FAMILY_MODULE))
    spec = importlib.util.spec_from_file_location("my_family", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    family = register(module.UnguardedIsoFamily())  # the one registration line
    yield family
    FAMILIES.pop(family.name)


def _dataset(path):
    """Noise-free windows of a known 2-term model at 4 points (model-made data: exact recovery)."""
    x_i = np.array([[3.0, 3.0], [4.5, 3.0], [3.0, 4.5], [4.5, 4.5]])
    c = np.broadcast_to(np.array([0.2, 0.02]), (4, 3, 1, 2)) * np.array([1.0, 0.8, 0.6])[None, :, None, None]
    d = np.broadcast_to(np.array([-3.0, -0.8]), (4, 3, 1, 2)).copy()
    truth = ExponentialModel(x_i, c, d, PlanarAlpha.uniform((64, 64), origin=(-4, -4), pitch=PITCH))
    n = 33
    origin = x_i - PITCH * n / 2
    R = truth.R_d_window(np.arange(4), origin, PITCH, (n, n))
    write_dataset(path, x_i, origin, R, PITCH)
    return truth


def test_a_seventh_family_is_one_module_and_one_line(seventh_family, tmp_path):
    truth = _dataset(tmp_path / "d.zarr")
    # the API: the family is a choice and fits like the isotropic model it varies (noise-free data
    # have no energy bound, so the guard never acts: the same parameters to the bit)
    ours = fit_planar(tmp_path / "d.zarr", "iso-unguarded", n_terms=2, max_rounds=2)
    iso = fit_planar(tmp_path / "d.zarr", "iso", n_terms=2, max_rounds=2)
    np.testing.assert_array_equal(ours.model.c, iso.model.c)
    np.testing.assert_array_equal(ours.model.d, iso.model.d)
    # and recovers the known model's total reflectance
    np.testing.assert_allclose(ours.model.total_reflectance(), truth.total_reflectance(), rtol=0.02)
    # the CLI: --model takes it, with its memory and time estimates, and the model file loads
    res = CliRunner().invoke(
        app,
        [
            "fit",
            str(tmp_path / "d.zarr"),
            "--model",
            "iso-unguarded",
            "--terms",
            "2",
            "--out",
            str(tmp_path / "m.model.zip"),
            "--rounds",
            "2",
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    model = load_model(tmp_path / "m.model.zip")
    np.testing.assert_allclose(model.c, ours.model.c, rtol=1e-5)
    info = CliRunner().invoke(app, ["info", str(tmp_path / "m.model.zip")])
    assert info.exit_code == 0, info.output


def test_an_unregistered_family_is_refused_in_one_line(tmp_path):
    _dataset(tmp_path / "d.zarr")
    res = CliRunner().invoke(
        app,
        ["fit", str(tmp_path / "d.zarr"), "--model", "iso-unguarded", "--out", str(tmp_path / "m.model.zip")],
    )
    assert res.exit_code == 2
    assert (
        "model: expected one of iso, aniso, dipole, burley, pbd, ddipole, got 'iso-unguarded'" in res.output
    )


def test_the_registry_describes_itself(seventh_family):
    """``fit --model``'s choices are said by the registry: each family's name and summary, in order, a
    registered family among them."""
    text = describe_families()
    assert text.startswith("iso | aniso (the paper's; planar data sets only) | dipole | burley | pbd")
    assert text.endswith(" | ddipole (directional dipole at normal incidence) | iso-unguarded.")


def test_the_cli_help_lists_the_registry():
    fit = typer.main.get_command(app).commands["fit"]
    text = next(p.help for p in fit.params if p.name == "model")
    assert text.startswith("auto: ") and text.endswith(
        " | " + describe_families()
    )  # the choice, then each family
