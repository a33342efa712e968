"""Eq. (1): integrals, a plain scalar implementation, sampling, eq. (2) and validation."""

import math

import numpy as np
import pytest
from scipy import stats
from scipy.integrate import dblquad, quad

from helpers import random_exponential_model
from translucency import TranslucencyError
from translucency.model import ExponentialModel, PlanarAlpha


def scalar_R_d(model, i, x_o):
    """Eq. (1) written out with plain Python loops and math, one pair at a time."""
    xi = model.x_i[i]
    dx, dy = x_o[0] - xi[0], x_o[1] - xi[1]
    r = math.hypot(dx, dy)
    theta = math.atan2(dy, dx) % (2 * math.pi)
    m, n = model.n_directions, model.n_terms
    # hat weights between the two neighbouring directions
    w = [0.0] * m
    if m == 1:
        w[0] = 1.0
    else:
        step = 2 * math.pi / m
        l0 = int(theta // step) % m
        t = theta / step - math.floor(theta / step)
        w[l0] += 1 - t
        w[(l0 + 1) % m] += t
    scale = [1.0, model.s_g[i], model.s_b[i]] if model.s_g is not None else [1.0, 1.0, 1.0]
    # α: nearest pixel
    a = model.alpha
    col = min(max(int(math.floor((x_o[0] - a.origin[0]) / a.pitch)), 0), a.values.shape[1] - 1)
    row = min(max(int(math.floor((x_o[1] - a.origin[1]) / a.pitch)), 0), a.values.shape[0] - 1)
    out = []
    for ch in range(3):
        block = 0 if model.c.shape[1] == 1 else ch
        total = 0.0
        for l in range(m):
            inner = sum(model.c[i, block, l, k] * math.exp(model.d[i, block, l, k] * r) for k in range(n))
            total += w[l] * inner
        out.append(a.values[row, col] * scale[ch] * total)
    return out


@pytest.mark.parametrize("m,colour", [(1, "shared"), (8, "shared"), (3, "per-channel"), (8, "per-channel")])
def test_vectorised_equals_scalar(rng, m, colour):
    model = random_exponential_model(rng, n_points=5, m=m, colour=colour)
    i = rng.integers(0, 5, 300)
    x_o = rng.uniform(-1, 9, (300, 2))
    fast = model.R_d(i, x_o)
    slow = np.array([scalar_R_d(model, ii, xo) for ii, xo in zip(i, x_o)])
    np.testing.assert_allclose(fast, slow, rtol=1e-12, atol=1e-300)


def test_window_equals_pairs(rng):
    model = random_exponential_model(rng, n_points=3, m=8)
    origin = np.array([[0.0, 0.0], [1.0, 2.0]])
    win = model.R_d_window([0, 2], origin, 0.25, (6, 7))
    assert win.shape == (2, 6, 7, 3)
    for b, i in enumerate([0, 2]):
        for row, col in [(0, 0), (5, 6), (2, 3)]:
            x = origin[b] + 0.25 * np.array([col + 0.5, row + 0.5])
            np.testing.assert_allclose(win[b, row, col], scalar_R_d(model, i, x), rtol=1e-12)


def test_isotropic_integral_is_two_pi_sum_c_over_d2(rng):
    model = random_exponential_model(rng, n_points=2, m=1)
    for i in range(2):
        c, d = model.c[i, 0, 0], model.d[i, 0, 0]
        prof = lambda r, c=c, d=d: 2 * np.pi * r * np.sum(c * np.exp(d * r))  # noqa: E731
        numeric = quad(prof, 0, np.inf, limit=200)[0]
        assert numeric == pytest.approx(2 * np.pi * np.sum(c / d**2), rel=1e-9)
        assert model.total_reflectance()[i, 0] == pytest.approx(numeric, rel=1e-9)
        np.testing.assert_allclose(
            model.total_reflectance()[i], numeric * np.array([1, model.s_g[i], model.s_b[i]])
        )


def test_anisotropic_integral_by_2d_quadrature(rng):
    """∫∫ R_d r dr dθ of the anisotropic profile, numerically, against (2π/m) Σ c/d²."""
    model = random_exponential_model(rng, n_points=1, m=4, n=2)
    zero = np.zeros(1, dtype=int)

    def integrand(r, theta):
        return r * model.profile(zero, np.array([r]), np.array([theta]))[0, 0]

    numeric = dblquad(integrand, 0, 2 * np.pi, 0, 40, epsabs=1e-10, epsrel=1e-8)[0]
    assert numeric == pytest.approx(model.total_reflectance()[0, 0], rel=1e-6)


def test_energy_radius_holds_the_fraction(rng):
    model = random_exponential_model(rng, n_points=4, m=1)
    rad = model.energy_radius(0.999)
    frac = model.energy_within(np.arange(4), rad) / model.total_reflectance()
    np.testing.assert_allclose(frac.min(axis=1), 0.999, atol=1e-9)
    # the enclosed energy itself against quadrature
    c, d = model.c[0, 0, 0], model.d[0, 0, 0]
    numeric = quad(lambda r: 2 * np.pi * r * np.sum(c * np.exp(d * r)), 0, rad[0])[0]
    assert model.energy_within(np.array([0]), rad[:1])[0, 0] == pytest.approx(numeric, rel=1e-9)


@pytest.mark.parametrize("channel", [None, 2])
def test_radius_sampler_matches_profile_chi2(rng, channel):
    model = random_exponential_model(rng, n_points=2, m=1, colour="per-channel")
    r, _ = model.sample(1, rng.random((100000, 4)), channel=channel)
    edges = np.concatenate([np.quantile(r, np.linspace(0, 1, 31))[:-1], [np.inf]])
    edges[0] = 0.0
    cdf = model.energy_within(np.full(edges.size, 1), edges)
    cdf = cdf.sum(axis=1) if channel is None else cdf[:, channel]
    expected = np.diff(cdf) / cdf[-1] * r.size
    observed = np.histogram(r, bins=edges)[0]
    chi2 = ((observed - expected) ** 2 / expected).sum()
    assert stats.chi2.sf(chi2, len(expected) - 1) > 1e-3


def test_angle_sampler_matches_anisotropic_profile(rng):
    """θ marginal of the anisotropic sampler against ∫ P(r, θ) r dr (χ² over 24 bins)."""
    model = random_exponential_model(rng, n_points=1, m=8, n=2)
    _, theta = model.sample(0, rng.random((100000, 4)), channel=0)
    edges = np.linspace(0, 2 * np.pi, 25)
    zero = np.zeros(1, dtype=int)
    dens = lambda t: quad(lambda r: r * model.profile(zero, np.array([r]), np.array([t]))[0, 0], 0, np.inf)[0]  # noqa: E731
    mass = np.array([quad(dens, a, b)[0] for a, b in zip(edges[:-1], edges[1:])])
    expected = mass / mass.sum() * theta.size
    observed = np.histogram(theta, bins=edges)[0]
    chi2 = ((observed - expected) ** 2 / expected).sum()
    assert stats.chi2.sf(chi2, 23) > 1e-3


# slow (39 s of the fast suite: scipy's dblquad calls the pdf point by point)
@pytest.mark.slow
def test_pdf_integrates_to_one(rng):
    model = random_exponential_model(rng, n_points=1, m=8)
    val = dblquad(lambda r, t: r * model.pdf(0, r, t), 0, 2 * np.pi, 0, 60, epsrel=1e-7)[0]
    assert val == pytest.approx(1.0, rel=1e-5)


def _params(d_value=-1.0, c_value=1.0):
    c = np.full((3, 1, 1, 3), 0.5)
    d = np.full((3, 1, 1, 3), -2.0)
    c[2, 0, 0, 1] = c_value
    d[2, 0, 0, 1] = d_value
    return c, d


@pytest.mark.parametrize(
    "d_value,c_value,needle",
    [
        (0.0, 1.0, "incident point 2: d[channel block 0, direction 0, term 1] = 0"),
        (0.3, 1.0, "d[channel block 0, direction 0, term 1] = 0.3, must be < 0"),
        (-1.0, -0.1, "incident point 2: c[channel block 0, direction 0, term 1] = -0.1"),
    ],
)
def test_eq2_violation_names_point_and_parameter(d_value, c_value, needle):
    c, d = _params(d_value, c_value)
    with pytest.raises(TranslucencyError, match="eq. \\(2\\) violated") as exc:
        ExponentialModel(np.zeros((3, 2)), c, d, PlanarAlpha.uniform((2, 2)), s_g=np.ones(3), s_b=np.ones(3))
    assert needle in str(exc.value)
    assert "\n" not in str(exc.value)


def test_bad_inputs_are_named():
    c, d = _params()
    alpha = PlanarAlpha.uniform((2, 2))
    with pytest.raises(TranslucencyError, match="s_g, s_b"):
        ExponentialModel(np.zeros((3, 2)), c, d, alpha)
    with pytest.raises(TranslucencyError, match="x_i: non-finite"):
        ExponentialModel([[0, 0], [np.nan, 0], [1, 1]], c, d, alpha, s_g=np.ones(3), s_b=np.ones(3))
    with pytest.raises(TranslucencyError, match="c: 3 incident points, but x_i has 2"):
        ExponentialModel(np.zeros((2, 2)), c, d, alpha, s_g=np.ones(2), s_b=np.ones(2))
    model = ExponentialModel(np.zeros((3, 2)), c, d, alpha, s_g=np.ones(3), s_b=np.ones(3))
    with pytest.raises(TranslucencyError, match=r"i: index 7 at \(0,\) out of range \[0, 3\)"):
        model.R_d([7], [[0.0, 0.0]])
    with pytest.raises(TranslucencyError, match="alpha: negative value"):
        PlanarAlpha(-np.ones((2, 2)), (0, 0), 1.0)
    with pytest.raises(TranslucencyError, match="fraction"):
        model.energy_radius(1.5)


def test_mesh_model_uses_tangent_frame(rng):
    model = random_exponential_model(rng, n_points=2, m=8, geometry="mesh")
    t, b, n = model.frame[0]
    x_o = model.x_i[0] + 0.7 * (np.cos(0.3) * t + np.sin(0.3) * b)
    r, theta = model.polar(np.array([0]), x_o[None])
    assert r[0] == pytest.approx(0.7)
    assert theta[0] == pytest.approx(0.3)
    np.testing.assert_allclose(
        model.R_d([0], x_o[None], alpha_o=[1.0])[0], model.profile(np.array([0]), r, theta)[0]
    )
