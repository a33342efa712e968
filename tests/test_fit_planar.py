"""Planar fitting: parameter recovery, agreement with scipy per point, alternation with α, bad input.

Model-generated data appear only in the parameter-recovery tests (the issue allows
exactly that); accuracy claims are checked on virtual-DISCO data in test_evaluate.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from helpers import exponential_terms
from translucency import TranslucencyError
from translucency.fit.planar import fit_planar
from translucency.fit.profile import fit_exponential_profile
from translucency.io.dataset import write_dataset
from translucency.model import BurleyModel, DipoleModel, ExponentialModel, PlanarAlpha, burley_R, dipole_R_d
from translucency.solvers.lm import fit_params_batched
from translucency.solvers.varpro import fit_exponentials_batched, nnls_small

PITCH = 0.25


def _grid_points(side=4, spacing=1.5, start=3.0):
    g = start + spacing * np.arange(side)
    xx, yy = np.meshgrid(g, g)
    return np.stack([xx.ravel(), yy.ravel()], axis=1)


def _windows(model, x_i, half=16):
    """Windows of (2 half + 1)² pixels centred on pixel-centred x_i, noise-free."""
    n = 2 * half + 1
    origin = x_i - PITCH * n / 2
    return origin, model.R_d_window(np.arange(len(x_i)), origin, PITCH, (n, n))


def test_nnls_small_matches_scipy_nnls():
    from scipy.optimize import nnls

    rng = np.random.default_rng(3)
    A = rng.normal(size=(50, 40, 3))
    b = rng.normal(size=(50, 40))
    K = np.einsum("bgk,bgl->bkl", A, A)
    k = np.einsum("bgk,bg->bk", A, b)
    c, cost = nnls_small(K, k, np.einsum("bg,bg->b", b, b))
    for i in range(50):
        ref, res = nnls(A[i], b[i])
        np.testing.assert_allclose(c[i], ref, atol=1e-9)
        assert cost[i] == pytest.approx(res**2, rel=1e-9, abs=1e-12)


def test_batched_varpro_equals_scipy_per_profile():
    """The batched solver reaches the same optimum as scipy's least_squares profile by profile."""
    rng = np.random.default_rng(5)
    r = np.unique(np.hypot(*np.mgrid[-16:17, -16:17]).ravel() * PITCH)[1:]
    c, d = exponential_terms(rng, 24)
    Y = np.einsum("bk,bgk->bg", c[:, 0, 0], np.exp(d[:, 0, 0][:, None, :] * r[None, :, None]))
    Y = Y * (1 + 0.03 * rng.normal(size=Y.shape))  # noisy: the optimum is not the truth
    cb, ab, cost = fit_exponentials_batched(r, 1 / Y, Y, 3)
    for b in range(24):
        ref = fit_exponential_profile(r, Y[b], 3)
        ref_cost = np.sum(((ref(r) - Y[b]) / Y[b]) ** 2)
        assert cost[b] <= ref_cost * (1 + 1e-4), b


def test_ring_recurrence_exponentials_equal_numpy_exp():
    """The solver's e^{-a r} (ring-to-ring products and a series to the mean radius) against np.exp."""
    from translucency.fit._windows import radius_groups
    from translucency.solvers.varpro import _exponentials

    r_px = np.hypot(*np.mgrid[-40:41, -40:41]).ravel()[None] * PITCH
    gid, r_g, r_base = radius_groups(r_px, PITCH, r_exact=1.0, radius_step=PITCH / 4)
    steps = np.diff(r_base[r_base > 1.1])
    assert np.mean(np.abs(steps - PITCH / 4) < 1e-9) > 0.7  # mostly consecutive rings: products, not exps
    for a in ([40.0, 3.0, 0.05], [8.0, 1.2, 0.3]):
        E = np.empty((3, r_g.size))
        _exponentials(r_g, r_base, np.array(a), E)
        np.testing.assert_allclose(E, np.exp(-np.array(a)[:, None] * r_g), rtol=1e-9, atol=1e-300)


def test_batched_lm_recovers_dipole_and_burley():
    r = np.linspace(0.25, 6, 60)
    sa, sp = np.array([0.003, 0.02, 0.1]), np.array([2.5, 1.0, 0.6])
    Y = dipole_R_d(r[None], sa[:, None], sp[:, None], 1.3)
    prof = lambda r, p: dipole_R_d(r[None], p[:, :1], p[:, 1:], 1.3)  # noqa: E731
    p, _ = fit_params_batched(prof, r, 1 / Y, Y, [(0.01, 1.0), (0.002, 3.0)])
    np.testing.assert_allclose(p, np.stack([sa, sp], 1), rtol=1e-5)
    Yb = burley_R(r[None], np.array([[0.4], [0.9]]), np.array([[0.5], [3.0]]))
    pb, _ = fit_params_batched(
        lambda r, p: burley_R(r[None], p[:, :1], p[:, 1:]), r, 1 / Yb, Yb, [(0.8, 1.0)]
    )
    np.testing.assert_allclose(pb, [[0.4, 0.5], [0.9, 3.0]], rtol=1e-6)


@pytest.mark.parametrize("colour", ["per-channel", "shared"])
def test_iso_parameter_recovery(tmp_path, colour):
    """Noise-free windows made by eq. (1): c, d, (s_g, s_b) and α come back to 1e-3."""
    rng = np.random.default_rng(11)
    x_i = _grid_points()
    P = len(x_i)
    c, d = exponential_terms(rng, P, C=3 if colour == "per-channel" else 1)
    alpha = PlanarAlpha.uniform((60, 60), (0.0, 0.0), PITCH)
    kw = {} if colour == "per-channel" else {"s_g": rng.uniform(0.6, 0.9, P), "s_b": rng.uniform(0.3, 0.6, P)}
    truth = ExponentialModel(x_i, c, d, alpha, **kw)
    origin, R = _windows(truth, x_i)
    ds = write_dataset(tmp_path / "d.zarr", x_i, origin, R, PITCH)
    fit = fit_planar(ds, "iso", colour=colour, radius_step=None, max_rounds=3)
    m = fit.model
    np.testing.assert_allclose(m.d, truth.d, rtol=1e-3)
    np.testing.assert_allclose(m.c, truth.c, rtol=1e-3)
    if colour == "shared":
        np.testing.assert_allclose(m.s_g, truth.s_g, rtol=1e-3)
        np.testing.assert_allclose(m.s_b, truth.s_b, rtol=1e-3)
    seen = m.alpha.values != 1.0  # unobserved pixels stay at 1
    np.testing.assert_allclose(m.alpha.values, 1.0, atol=1e-3)
    assert seen.sum() > 100 and not fit.flagged.any()


def test_alpha_recovery_with_modulation(tmp_path):
    """A modulation texture with mean 1 over the observed pixels is recovered by the alternation."""
    rng = np.random.default_rng(12)
    x_i = _grid_points(side=5, spacing=1.0)
    P = len(x_i)
    c, d = exponential_terms(rng, P)
    yy, xx = np.mgrid[0:40, 0:40] * PITCH
    values = 1.0 + 0.3 * np.sin(xx * 1.3) * np.cos(yy * 0.9)
    truth = ExponentialModel(x_i, c, d, PlanarAlpha(values, (0.0, 0.0), PITCH))
    origin, R = _windows(truth, x_i, half=12)
    ds = write_dataset(tmp_path / "d.zarr", x_i, origin, R, PITCH)
    fit = fit_planar(ds, "iso", radius_step=None, max_rounds=40, tol=1e-9)
    # compare on the sample grid of the fit, up to the global scale that α = 1 on average fixes
    a_fit = fit.model.alpha
    centres = a_fit.origin + PITCH * (
        np.stack(np.meshgrid(np.arange(a_fit.shape[1]), np.arange(a_fit.shape[0])), -1) + 0.5
    )
    a_true = truth.alpha.at(centres)
    scale = np.median(a_fit.values / a_true)
    err = np.abs(a_fit.values / (scale * a_true) - 1)
    assert np.quantile(err, 0.9) < 0.02
    pred = fit.model.R_d_window(np.arange(P), origin, PITCH, R.shape[1:3])
    assert np.linalg.norm(pred - R) / np.linalg.norm(R) < 0.01
    assert fit.history[-1] < fit.history[1]  # the alternation lowers the objective


def test_pooled_alpha_keeps_the_noise_of_a_sparse_grid_out(tmp_path):
    """2 × 2 points, α = 1, photon noise (10 % of ‖R‖): per pixel α follows the noise of the ≤ 4 windows
    over each pixel (its spread ~0.2) and the model with it; pooled over a 1 mm disc α stays near 1 and the
    model lies closer to the noise-free windows.  ``alpha_radius=0`` is the per-pixel fit, bit for bit."""
    rng = np.random.default_rng(21)
    x_i = _grid_points(side=2)
    c, d = exponential_terms(rng, len(x_i))
    truth = ExponentialModel(x_i, c, d, PlanarAlpha.uniform((40, 40), (0.0, 0.0), PITCH))
    origin, R = _windows(truth, x_i, half=10)
    photons = 20_000
    counts = rng.poisson(R * photons * PITCH**2)
    ds = write_dataset(
        tmp_path / "d.zarr", x_i, origin, counts / (photons * PITCH**2), PITCH, photons=photons
    )
    ok = np.hypot(*np.mgrid[-10:11, -10:11]) >= 1  # the fit's default exclusion: one pixel
    fits, errors = {}, {}
    for rad in (None, 0.0, 1.0):
        fits[rad] = fit_planar(ds, "iso", n_terms=2, alpha_radius=rad)
        pred = fits[rad].model.R_d_window(np.arange(len(x_i)), origin, PITCH, R.shape[1:3])
        errors[rad] = np.linalg.norm((pred - R)[:, ok]) / np.linalg.norm(R[:, ok])
    np.testing.assert_array_equal(fits[0.0].model.alpha.values, fits[None].model.alpha.values)
    np.testing.assert_array_equal(fits[0.0].model.c, fits[None].model.c)
    assert "alpha_radius" not in fits[None].options and fits[1.0].options["alpha_radius"] == 1.0
    spread = {rad: float(fits[rad].model.alpha.values.std()) for rad in (None, 1.0)}
    assert spread[None] > 0.1 and spread[1.0] < 0.3 * spread[None], spread
    assert errors[1.0] < 0.7 * errors[None], errors
    with pytest.raises(TranslucencyError, match="alpha_radius"):
        fit_planar(ds, "iso", alpha_radius=-1.0)


def test_aniso_recovers_directional_profiles(tmp_path):
    rng = np.random.default_rng(13)
    x_i = _grid_points(side=3)
    P, m = len(x_i), 8
    c, d = exponential_terms(rng, P, m=m)
    truth = ExponentialModel(x_i, c, d, PlanarAlpha.uniform((60, 60), (0.0, 0.0), PITCH))
    origin, R = _windows(truth, x_i)
    ds = write_dataset(tmp_path / "d.zarr", x_i, origin, R, PITCH)
    fit = fit_planar(ds, "aniso", n_directions=m, radius_step=None, max_rounds=6, sweeps=4, tol=1e-12)
    pred = fit.model.R_d_window(np.arange(P), origin, PITCH, R.shape[1:3])
    rel = np.linalg.norm(pred - R) / np.linalg.norm(R)
    iso = fit_planar(ds, "iso", radius_step=None, max_rounds=2).model
    rel_iso = np.linalg.norm(iso.R_d_window(np.arange(P), origin, PITCH, R.shape[1:3]) - R) / np.linalg.norm(
        R
    )
    assert rel < 0.01 and rel < 0.2 * rel_iso


@pytest.mark.parametrize("kind,cls", [("dipole", DipoleModel), ("burley", BurleyModel)])
def test_baseline_recovery(tmp_path, kind, cls):
    x_i = _grid_points(side=3)
    P = len(x_i)
    rng = np.random.default_rng(14)
    alpha = PlanarAlpha.uniform((60, 60), (0.0, 0.0), PITCH)
    if kind == "dipole":
        p1, p2 = rng.uniform(0.002, 0.02, (P, 3)), rng.uniform(0.8, 2.5, (P, 3))
        truth = DipoleModel(x_i, p1, p2, 1.3, alpha)
    else:
        p1, p2 = rng.uniform(0.3, 0.9, (P, 3)), rng.uniform(0.5, 2.0, (P, 3))
        truth = BurleyModel(x_i, p1, p2, alpha)
    origin, R = _windows(truth, x_i)
    fit = fit_planar(
        write_dataset(tmp_path / "d.zarr", x_i, origin, R, PITCH, eta=1.3),
        kind,
        radius_step=None,
        max_rounds=3,
    )
    got = (fit.model.sigma_a, fit.model.sigma_s_prime) if kind == "dipole" else (fit.model.A, fit.model.s)
    np.testing.assert_allclose(got[0], p1, rtol=2e-3)
    np.testing.assert_allclose(got[1], p2, rtol=2e-3)


def _iso_truth(seed, side):
    """A random per-channel isotropic model on a side × side grid, α = 1, and its windows."""
    rng = np.random.default_rng(seed)
    x_i = _grid_points(side=side)
    c, d = exponential_terms(rng, len(x_i))
    truth = ExponentialModel(x_i, c, d, PlanarAlpha.uniform((60, 60), (0.0, 0.0), PITCH))
    return rng, x_i, truth, *_windows(truth, x_i)


def test_masked_and_nan_windows_are_flagged(tmp_path):
    _, x_i, truth, origin, R = _iso_truth(15, 3)
    mask = np.ones(R.shape[:3], bool)
    mask[2] = False
    R[5] = np.nan
    fit = fit_planar(
        write_dataset(tmp_path / "d.zarr", x_i, origin, R, PITCH, mask=mask), "iso", max_rounds=2
    )
    assert fit.flagged.tolist() == [i in (2, 5) for i in range(len(x_i))]
    assert np.isfinite(fit.model.c).all() and np.isfinite(fit.model.alpha.values).all()
    assert (fit.model.c[[2, 5]] == 0).all()
    ok = [i for i in range(len(x_i)) if i not in (2, 5)]
    np.testing.assert_allclose(fit.model.d[ok], truth.d[ok], rtol=1e-2)


def test_interrupted_fit_resumes_identically(tmp_path):
    rng, x_i, truth, origin, R = _iso_truth(16, 4)
    ds = write_dataset(tmp_path / "d.zarr", x_i, origin, R * (1 + 0.05 * rng.normal(size=R.shape)), PITCH)
    full = fit_planar(ds, "iso", max_rounds=3, chunk_points=4)
    ckpt = tmp_path / "fit.partial.npz"

    class Stop(Exception):
        pass

    def interrupt(done, total, message):
        if done == 3:
            raise Stop

    with pytest.raises(Stop):
        fit_planar(ds, "iso", max_rounds=3, chunk_points=4, checkpoint=ckpt, progress=interrupt)
    assert ckpt.exists()
    resumed = fit_planar(ds, "iso", max_rounds=3, chunk_points=4, checkpoint=ckpt)
    np.testing.assert_array_equal(resumed.model.c, full.model.c)
    np.testing.assert_array_equal(resumed.model.alpha.values, full.model.alpha.values)
    assert not ckpt.exists()


def test_bad_options_and_datasets(tmp_path):
    x_i = _grid_points(side=2)
    origin = x_i - PITCH * 9 / 2
    ds = write_dataset(tmp_path / "d.zarr", x_i, origin, np.full((4, 9, 9, 3), 0.01), PITCH)
    with pytest.raises(TranslucencyError, match="model"):
        fit_planar(ds, "gauss")
    with pytest.raises(TranslucencyError, match="terms"):
        fit_planar(ds, "iso", n_terms=7)
    with pytest.raises(TranslucencyError, match="directions"):
        fit_planar(ds, "aniso", n_directions=1)
    with pytest.raises(TranslucencyError, match="no such data set"):
        fit_planar(tmp_path / "missing.zarr")
    import shutil

    shutil.rmtree(tmp_path / "d.zarr" / "variance")
    with pytest.raises(TranslucencyError, match="missing or unreadable array 'variance'"):
        fit_planar(tmp_path / "d.zarr")


def test_the_fit_does_not_depend_on_the_chunking():
    """The embedded data set (1,024 points) fitted in chunks of 32 and of 256: the same per-point totals."""
    from translucency.data import default_dataset_path

    fits = [fit_planar(default_dataset_path(), "iso", max_rounds=2, chunk_points=k) for k in (32, 256)]
    totals = [f.model.total_reflectance() for f in fits]
    np.testing.assert_allclose(totals[0], totals[1], rtol=1e-6)
    np.testing.assert_allclose(fits[0].model.alpha.values, fits[1].model.alpha.values, rtol=1e-6, atol=1e-9)
