"""The held-out error's noise floor: on data made of an exact model profile plus Gaussian noise of known
variance, the true profile's held-out error is the noise (ratio 1 within its spread), a profile off by a
known factor gives the ratio the closed form says, a fit of the right structure comes close to 1, the
variance is summed over exactly the pairs the error is, on planar and mesh data; and what ``fit`` prints."""

import copy

import numpy as np
import pytest
import trimesh
import zarr
from typer.testing import CliRunner

import translucency as tl
from helpers import exponential_terms
from translucency.cli.app import app
from translucency.evaluate.mesh_errors import TALLY_VARIANCE_FACTOR
from translucency.fit.held_out import held_out_terms, mesh_held_out_terms, vertex_half
from translucency.fit.mesh import fit_mesh
from translucency.fit.mesh_pairs import read_pairs
from translucency.fit.planar import NEAR_MM, fit_planar
from translucency.fit.structure import _noise
from translucency.io.dataset import open_dataset, write_dataset
from translucency.io.mesh_dataset import open_mesh_dataset
from translucency.io.point_subset import point_subset
from translucency.model import ExponentialModel, PlanarAlpha

runner = CliRunner()

PITCH = 0.25
#: the noise's standard deviation relative to R_d (Gaussian, independent per pixel and channel)
REL = 0.1


@pytest.fixture(scope="module")
def noisy(tmp_path_factory):
    """A 4 x 4 grid of incident points 1.5 mm apart, 33 x 33 windows of an exact 3-term profile per point
    and channel (α = 1) plus Gaussian noise of standard deviation REL R_d, its variance (REL R_d)² written."""
    rng = np.random.default_rng(21)
    g = 3.0 + 1.5 * np.arange(4)
    x_i = np.stack([a.ravel() for a in np.meshgrid(g, g)], axis=1)
    c, d = exponential_terms(rng, len(x_i))
    truth = ExponentialModel(x_i, c, d, PlanarAlpha.uniform((60, 60), (0.0, 0.0), PITCH))
    n = 33
    origin = x_i - PITCH * n / 2
    mu = truth.R_d_window(np.arange(len(x_i)), origin, PITCH, (n, n))
    y = mu * (1 + REL * rng.standard_normal(mu.shape))
    path = tmp_path_factory.mktemp("noisy") / "d.zarr"
    ds = write_dataset(path, x_i, origin, y, PITCH, variance=(REL * mu) ** 2)
    return ds, truth


def _as_truth(fit, truth, factor=1.0):
    """The half fit ``fit`` with its model replaced by the truth's profiles times ``factor``, α = 1."""
    exact = copy.deepcopy(fit)
    exact.model.c, exact.model.d = truth.c * factor, truth.d
    exact.model.alpha.values[...] = 1.0
    return exact


def _ratio(e, y, v):
    noise, se = _noise(e, y, v)
    return np.sqrt(e.sum() / y.sum()) / noise, se, noise


def test_the_true_profiles_held_out_error_is_the_noise(noisy):
    ds, truth = noisy
    fit = fit_planar(ds, "iso", half=0, radius_step=None, max_rounds=2)
    e, y, v = held_out_terms(_as_truth(fit, truth), ds, near=NEAR_MM, variance=True)
    ratio, se, noise = _ratio(e, y, v)
    # the noise of the held-out pairs: Σ(REL μ)² / Σ(μ + n)² = REL² / (1 + REL²) up to the draw
    assert noise == pytest.approx(REL / np.sqrt(1 + REL**2), rel=0.1)
    assert 0 < se < 0.05 and abs(ratio - 1) < 3 * se


def test_a_profile_off_by_a_factor_gives_the_closed_form_ratio(noisy):
    """E² = Σ((k − 1)μ − n)² / Σy² ≈ (k − 1)² (1 − N²) + N², so E / N = √((k − 1)² (1 − N²) / N² + 1)."""
    ds, truth = noisy
    fit = fit_planar(ds, "iso", half=0, radius_step=None, max_rounds=2)
    for k in (0.8, 1.1, 1.5):
        e, y, v = held_out_terms(_as_truth(fit, truth, k), ds, near=NEAR_MM, variance=True)
        ratio, _, noise = _ratio(e, y, v)
        expected = np.sqrt((k - 1) ** 2 * (1 - noise**2) / noise**2 + 1)
        assert ratio == pytest.approx(expected, rel=0.05), k


def test_the_variance_is_summed_over_the_scored_pairs(noisy, tmp_path):
    """With variance = q y² written, Σσ² over any set of pairs is q Σy² over the same set: exactly."""
    ds, _ = noisy
    sub = point_subset(ds, np.arange(ds.n_points), tmp_path / "copy.zarr")
    R = np.asarray(sub.group["R_d"][...], dtype=np.float64)
    zarr.open_group(str(sub.path), mode="r+")["variance"][...] = (0.3 * R**2).astype(np.float32)
    fit = fit_planar(sub, "iso", half=1, radius_step=None, max_rounds=1)
    e, y, v = held_out_terms(fit, open_dataset(sub.path), near=NEAR_MM, variance=True)
    np.testing.assert_allclose(v, 0.3 * y, rtol=1e-5)
    for before, now in zip(held_out_terms(fit, sub, near=NEAR_MM), (e, y), strict=True):
        np.testing.assert_array_equal(before, now)  # the two terms as without the variance


def test_a_fit_of_the_right_structure_is_near_its_noise_and_says_so(noisy):
    """The chosen structure's record carries the noise and the ratio; the line leads with the ratio."""
    ds, _ = noisy
    record = fit_planar(ds, radius_step=None).options["structure"]
    assert record["noise"] == pytest.approx(REL / np.sqrt(1 + REL**2), rel=0.1)
    assert record["ratio_to_noise"] == pytest.approx(record["held_out"] / record["noise"])
    # α per pixel is fitted from a few windows' noise, so a fit sits a little above its floor
    assert 1 - 3 * record["ratio_se"] < record["ratio_to_noise"] < 1.15
    line = record["summary"]
    assert line.startswith(f"held-out error {record['ratio_to_noise']:.2f} × the data's own noise")
    assert "on the pixels the fit did not see" in line and "structure iso" in line


def test_fit_prints_the_ratio_and_a_model_off_the_noise_is_told(noisy, tmp_path):
    ds, _ = noisy
    res = runner.invoke(app, ["fit", str(ds.path), "--out", str(tmp_path / "m.model.zip")])
    assert res.exit_code == 0, res.output
    assert "× the data's own noise" in " ".join(res.output.split())
    # a data set whose recorded noise is a tenth of its real one: the fit misses far more than "the noise"
    sub = point_subset(ds, np.arange(ds.n_points), tmp_path / "quiet.zarr")
    var = np.asarray(sub.group["variance"][...], dtype=np.float64)
    zarr.open_group(str(sub.path), mode="r+")["variance"][...] = (var / 100).astype(np.float32)
    record = fit_planar(open_dataset(sub.path), radius_step=None).options["structure"]
    assert record["ratio_to_noise"] > 5 and "beyond the noise the model misses" in record["summary"]


@pytest.fixture(scope="module")
def ball(tmp_path_factory):
    """A 4 mm ball of homogeneous marble, 12 incident points (a simulated mesh data set)."""
    mesh = trimesh.creation.icosphere(3, radius=4.0)
    path = tmp_path_factory.mktemp("ball") / "ball.zarr"
    kw = {"voxel_mm": 1.0, "points": 12, "photons": 3000, "index_matched": True}
    return tl.acquire_mesh(mesh, path, "homogeneous:marble", seed=0, **kw)


def test_mesh_noise_is_the_tally_variance_weighted_as_the_error(ball, tmp_path):
    """Simulated: σ² = TALLY_VARIANCE_FACTOR R_d / (N A_v), weighted by A_v: Σ A_v σ² = factor Σ R_d / N over
    the held-out pairs; measured (``R_d_var`` stored): Σ A_v R_d_var, here q Σ A_v R_d² = q ‖y‖²."""
    fit = fit_mesh(ball.path, "iso", half=0, max_rounds=1)
    group = open_mesh_dataset(ball.path).group
    e, y, v = mesh_held_out_terms(fit, group, variance=True)
    vertices = np.asarray(group["vertices"][...], dtype=np.float64)
    x_i = np.asarray(fit.model.x_i, dtype=np.float64)
    R, _, valid = read_pairs(group, vertices, x_i, float(fit.options["exclusion_mm"]), 0, ball.n_points)
    held = valid & (vertex_half(np.arange(ball.n_points), np.arange(len(vertices))) == 1)
    held &= ~fit.flagged[:, None]
    expected = TALLY_VARIANCE_FACTOR / ball.header["photons"] * np.where(held, R.sum(2), 0.0).sum(1)
    np.testing.assert_allclose(v, expected, rtol=1e-5)
    ratio, se, _ = _ratio(e, y, v)
    one = fit_mesh(ball.path, "iso", n_terms=1, half=0, max_rounds=1)  # one term misses far more
    assert 0.8 < ratio < 2.5 and se > 0 and _ratio(*mesh_held_out_terms(one, group, variance=True))[0] > ratio
    sub = point_subset(ball, np.arange(ball.n_points), tmp_path / "measured.zarr")
    root = zarr.open_group(str(sub.path), mode="r+")
    R = np.asarray(root["R_d"][...], dtype=np.float32)
    root.create_array("R_d_var", data=0.3 * R**2, chunks=root["R_d"].chunks)
    e2, y2, v2 = mesh_held_out_terms(fit, open_mesh_dataset(sub.path).group, variance=True)
    np.testing.assert_allclose(v2, 0.3 * y2, rtol=1e-5)
    np.testing.assert_allclose(e2, e, rtol=1e-6)
