"""Physical guard rails (model/bounds.py): closed-form totals, energy radii against the object, and the tools
that must not call an unphysical model valid."""

import numpy as np
import pytest
from scipy.integrate import quad
from typer.testing import CliRunner

from helpers import random_exponential_model
from translucency import ExponentialModel, PlanarAlpha, load_model, save_model
from translucency.cli.app import app
from translucency.io.model_file import read_header
from translucency.model import check_physics, model_extent

runner = CliRunner()


def test_bounds_against_a_plain_integral(rng):
    """ρ = ∫ 2πr P(r) dr by quadrature and the 99.9 % radius by root finding, point by point."""
    model = random_exponential_model(rng, n_points=6, n=3)
    check = check_physics(model)
    for i in range(6):
        c, d = model.c[i, 0, 0], model.d[i, 0, 0]

        def profile(r, c=c, d=d):
            return 2 * np.pi * r * np.sum(c * np.exp(d * r))

        rho = quad(profile, 0, np.inf)[0]
        scale = np.array([1.0, model.s_g[i], model.s_b[i]])
        np.testing.assert_allclose(check.total[i], rho * scale, rtol=1e-6)
        r99 = check.radius[i]
        assert quad(profile, 0, r99)[0] == pytest.approx(0.999 * rho, rel=1e-4)
    assert check.ok and check.summary()["over_albedo"] == []


def test_unphysical_points_are_flagged_in_the_file_and_by_info(tmp_path, rng):
    model = random_exponential_model(rng, n_points=5)
    c = model.c.copy()
    c[2] *= 400.0  # reflects far more than it receives
    d = model.d.copy()
    d[4] = -0.004  # a profile that would need metres to decay, on an 8 mm sample
    bad = ExponentialModel(model.x_i, c, d, model.alpha, s_g=model.s_g, s_b=model.s_b)
    check = check_physics(bad)
    assert check.over_albedo.tolist() == [False, False, True, False, True]  # 2π·c/d² also explodes at 4
    assert check.beyond_object.tolist() == [False, False, False, False, True]
    assert model_extent(bad) == pytest.approx(np.hypot(16, 16) * 0.5)
    path = save_model(bad, tmp_path / "bad.model.zip")
    physics = read_header(path)["physics"]
    assert physics["over_albedo"] == [2, 4] and physics["beyond_object"] == [4]
    res = runner.invoke(app, ["info", str(path)])
    assert res.exit_code == 1, res.output
    assert "not physical" in res.output and "yes" not in res.output
    good = save_model(model, tmp_path / "good.model.zip")
    res = runner.invoke(app, ["info", str(good)])
    assert res.exit_code == 0 and "yes" in res.output
    assert load_model(good).n_points == 5


def test_extent_of_a_planar_sample():
    alpha = PlanarAlpha.uniform((30, 40), pitch=0.25)
    m = ExponentialModel([[0.0, 0.0]], [[[[0.01]]]], [[[[-2.0]]]], alpha, s_g=[1.0], s_b=[1.0])
    assert model_extent(m) == pytest.approx(12.5)


def test_info_json_is_one_object_for_scripts(tmp_path, rng):
    import json

    path = save_model(random_exponential_model(rng, n_points=3), tmp_path / "m.model.zip")
    res = runner.invoke(app, ["info", str(path), "--json"])
    assert res.exit_code == 0, res.output
    fields = json.loads(res.output)
    assert fields["path"] == str(path) and fields["valid"] is True and fields["n_points"] == 3
