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


# -- issue 22: what "the object" is, the share of the energy beyond it, the energy bound per family --------


def _one_point(c, d, alpha=None, **kw):
    """A shared-colour exponential model of one point at the centre of a 20 mm α (or ``alpha``)."""
    alpha = alpha or PlanarAlpha.uniform((40, 40), origin=(-10.0, -10.0), pitch=0.5)
    return ExponentialModel([[0.0, 0.0]], c, d, alpha, s_g=[1.0], s_b=[1.0], **kw)


def test_the_share_beyond_a_sample_against_a_plain_integral():
    """b = ∫dθ ∫_{R(θ)}^∞ P r dr / ρ on a rectangle the point is off-centre in: the closed form of the sums
    of exponentials and the baselines' enclosed-energy path against 2-D quadrature."""
    from scipy.integrate import quad as quad1

    from translucency.model import Rectangle, ReflectanceModel, check_physics
    from translucency.model.bounds import N_ANGLES

    c, a = np.array([0.02, 0.004]), np.array([1.2, 0.3])
    model = _one_point(c.reshape(1, 1, 1, 2), -a.reshape(1, 1, 1, 2))
    model.extent = Rectangle((-3.0, -5.0), (9.0, 4.0))  # 3, 9, 5 and 4 mm to the walls
    theta = 2 * np.pi * (np.arange(N_ANGLES) + 0.5) / N_ANGLES
    dist = model.extent.distance(model.x_i, theta)

    def radial_tail(R):  # ∫_R^∞ Σ c e^{-a r} r dr
        return quad1(lambda r: np.sum(c * np.exp(-a * r)) * r, R, np.inf)[0]

    exact = quad1(lambda t: radial_tail(model.extent.distance(model.x_i, np.array([t]))[0, 0]), 0, 2 * np.pi,
                  limit=200)[0]  # fmt: skip
    rho = 2 * np.pi * np.sum(c / a**2)
    check = check_physics(model)
    assert check.beyond[0] == pytest.approx(exact / rho, rel=2e-3)
    generic = ReflectanceModel.energy_beyond(model, dist)  # the baselines' path: ρ − E(R(θ)), averaged
    np.testing.assert_allclose(generic, model.energy_beyond(dist), rtol=1e-9)


def test_a_model_of_total_1_5_is_not_physical(tmp_path):
    """2π Σ c/d² = 1.5: flagged as reflecting more than it receives, in the check, the file and `info`."""
    model = _one_point([[[[1.5 / (2 * np.pi)]]]], [[[[-1.0]]]])
    check = check_physics(model)
    assert check.over_albedo.tolist() == [True] and check.beyond_object.tolist() == [False]
    assert "reflect more than they receive" in check.describe() and "1.5 > 1" in check.describe()
    path = save_model(model, tmp_path / "bright.model.zip")
    assert read_header(path)["physics"]["over_albedo"] == [0]
    res = runner.invoke(app, ["info", str(path)])
    assert res.exit_code == 1 and "not physical" in res.output


def test_energy_far_beyond_a_small_sample_is_not_physical(tmp_path):
    """A profile that is physical on a semi-infinite slab places 90 % of its light beyond a 6 mm sample."""
    from translucency.model import Rectangle, SemiInfinite

    model = _one_point([[[[1e-4]]]], [[[[-0.05]]]])  # ρ = 0.25 with a 20 mm fall-off
    model.extent = Rectangle((-3.0, -3.0), (3.0, 3.0))
    check = check_physics(model)
    assert check.beyond_object.tolist() == [True] and not check.over_albedo.any()
    assert check.beyond[0] > 0.9 and "spread light beyond the object" in check.describe()
    path = save_model(model, tmp_path / "wide.model.zip")
    physics = read_header(path)["physics"]
    assert physics["beyond_object"] == [0] and physics["max_beyond_object"] > 0.9
    assert load_model(path).extent.as_dict() == model.extent.as_dict()  # the object travels with the file
    assert runner.invoke(app, ["info", str(path)]).exit_code == 1
    model.extent = SemiInfinite()  # the same profile on Jensen's kind of material: no edge
    assert check_physics(model).ok
    path = save_model(model, tmp_path / "slab.model.zip")
    res = runner.invoke(app, ["info", str(path)])
    assert res.exit_code == 0, res.output
    assert "semi-infinite" in _flat(res.output)


def test_an_anisotropic_model_with_a_direction_over_1(tmp_path):
    """m = 2 directions: one at 2.5, the other at 0.3 — the blend reflects 1.4 of the light (flagged);
    one direction at 1.3 beside one at 0.5 reflects 0.9 (physical: fibres carry light along them), and its
    direction's own total is reported."""
    alpha = PlanarAlpha.uniform((40, 40), origin=(-10.0, -10.0), pitch=0.5)
    unit = 1.0 / (2 * np.pi)  # c of a total of 1 with d = −1

    def aniso(r0, r1):
        c = np.array([[[[r0 * unit], [r1 * unit]]]])
        return ExponentialModel([[0.0, 0.0]], c, np.full(c.shape, -1.0), alpha, s_g=[1.0], s_b=[1.0])

    bad = aniso(2.5, 0.3)
    check = check_physics(bad)
    assert check.over_albedo.tolist() == [True] and check.total[0, 0] == pytest.approx(1.4)
    assert check.summary()["max_direction_total"] == pytest.approx(2.5)
    assert "reflect more than they receive" in check.describe()
    assert runner.invoke(app, ["info", str(save_model(bad, tmp_path / "bad.model.zip"))]).exit_code == 1
    good = aniso(1.3, 0.5)
    check = check_physics(good)
    assert check.ok and check.summary()["max_direction_total"] == pytest.approx(1.3)


def test_the_energy_bound_allows_a_tally_its_noise():
    """ρ ≤ 1 + 10⁻³, plus 3 standard errors of a tally's total at its noisiest, 3 / (2√N)."""
    from translucency.model.bounds import albedo_bound

    model = _one_point([[[[1.008 / (2 * np.pi)]]]], [[[[-1.0]]]])
    assert not check_physics(model).ok  # no photon count recorded: float16 / quadrature round-off only
    model.tally_photons = 20_000  # 3 / (2√20000) = 0.0106
    assert albedo_bound(model) == pytest.approx(1.001 + 0.0106066, rel=1e-6)
    assert check_physics(model).ok
    model.c = model.c * 1.02 / 1.008
    assert check_physics(model).over_albedo.tolist() == [True]


def _flat(text):
    return " ".join(text.replace("│", " ").split())


def test_a_planar_fit_records_its_sample_and_keeps_every_bound(planar_scan, tmp_path):
    """A noisy scan (1,500 photons) fitted with every exponential family: the model knows the sample it
    was fitted on (the data set's 12 × 12 mm slab, the tally's photons), the file carries both, and the
    anisotropic directions' blend stays within the isotropic energy guard's bound."""
    from translucency.fit.planar import TOTAL_TOLERANCE, fit_planar

    ds = planar_scan("fibers", side=3, span=2.0, photons=1_500, seed=7)
    measured = ds["total_diffuse"].astype(np.float64)
    for kind, kw in (("iso", {}), ("aniso", {"n_directions": 4})):
        fit = fit_planar(ds, kind, **kw)
        assert fit.model.extent.as_dict() == {"kind": "rectangle", "lo": [0.0, 0.0], "hi": [12.0, 12.0]}
        assert fit.model.tally_photons == 1_500
        check = check_physics(fit.model)
        assert check.ok, (kind, check.describe())
        bound = np.minimum(1.0, (1 + TOTAL_TOLERANCE) * measured)
        assert (check.total <= bound * (1 + 0.02)).all(), kind  # α's normalisation moves it ≲ 1 %
        back = load_model(save_model(fit.model, tmp_path / f"{kind}.model.zip"))
        assert back.extent.as_dict() == fit.model.extent.as_dict() and back.tally_photons == 1_500


def test_the_model_built_by_hand_is_physical(tmp_path, monkeypatch):
    """The how-to "Build a model by hand" runs as written, and the model it builds passes the bounds."""
    import re
    from pathlib import Path

    page = Path(__file__).resolve().parents[1] / "docs" / "how-to" / "model-by-hand.md"
    block = re.search(r"```python\n(.*?)```", page.read_text(), re.S).group(1)
    monkeypatch.chdir(tmp_path)  # the page writes m.model.zip where it runs
    namespace = {}
    exec(compile(block, str(page), "exec"), namespace)
    check = check_physics(namespace["model"])
    assert check.ok, check.describe()
    assert check.total.max() < 1.0


def test_jensens_materials_are_semi_infinite_slabs(tmp_path):
    """The demo's model of Jensen's fits: no edge under skim milk's 300 mm profile; `info` exits 0."""
    from translucency.evaluate.baselines import fits_model, material_profiles
    from translucency.model import MATERIALS

    model = fits_model([material_profiles(m) for m in MATERIALS.values()])
    check = check_physics(model)
    assert check.ok and check.radius.max() > 100 and np.isinf(check.size_mm)
    assert check.summary()["size_mm"] is None and check.summary()["extent"] == "semi-infinite"
    path = save_model(model, tmp_path / "dipole_fits.model.zip")
    assert read_header(path)["object"] == {"extent": {"kind": "semi-infinite"}}
    assert runner.invoke(app, ["info", str(path)]).exit_code == 0


def test_the_readme_fit_example_writes_a_valid_model(tmp_path):
    """The README's command-line session (`acquire planar --material marble --grid 8 --photons 10000`, then
    `fit --model iso`): before the bounds were right, `fit` warned of 11 unphysical points."""
    data = tmp_path / "m.zarr"
    args = "acquire planar --material marble --grid 8 --photons 10000".split() + ["--out", str(data)]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    for kind in ("iso", "aniso"):
        out = tmp_path / f"{kind}.model.zip"
        res = runner.invoke(app, ["fit", str(data), "--model", kind, "--out", str(out)])
        assert res.exit_code == 0, res.output
        assert "not physical" not in res.output, res.output
        res = runner.invoke(app, ["info", str(out)])
        assert res.exit_code == 0, res.output
