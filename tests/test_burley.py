"""Christensen–Burley normalized diffusion: normalisation, closed-form energy, exact sampling."""

import numpy as np
import pytest
from scipy import stats
from scipy.integrate import quad

from translucency.model import BurleyModel, PlanarAlpha, burley_energy_within, burley_R, burley_shape


@pytest.mark.parametrize("A,s", [(0.8, 2.0), (0.3, 0.5), (0.95, 7.0)])
def test_integrates_to_A(A, s):
    numeric = quad(lambda r: 2 * np.pi * r * burley_R(r, A, s), 0, np.inf, limit=200)[0]
    assert numeric == pytest.approx(A, rel=1e-6)  # R_MIN clamp changes the integral by < 1e-7
    assert burley_energy_within(np.inf, A, s) == pytest.approx(A, rel=1e-15)


@pytest.mark.parametrize("R", [0.05, 0.5, 3.0])
def test_energy_within_matches_quadrature(R):
    numeric = quad(lambda r: 2 * np.pi * r * burley_R(r, 0.7, 1.3), 0, R)[0]
    assert burley_energy_within(R, 0.7, 1.3) == pytest.approx(numeric, rel=1e-6)


def test_shape_rules():
    # searchlight at A = 0.8: s~ = 1.85 - 0.8 = 1.05; with mfp 0.5 mm -> 2.1 / mm
    assert burley_shape(0.8, 0.5) == pytest.approx(2.1)
    assert burley_shape(0.8, 1.0, "diffuse") == pytest.approx(1.1)
    assert burley_shape(0.33, 2.0, "dmfp") == pytest.approx(1.75)


def test_sampler_chi2():
    model = BurleyModel([[0.0, 0.0]], [[0.8, 0.6, 0.4]], [[2.0, 1.0, 0.5]], PlanarAlpha.uniform((1, 1)))
    rng = np.random.default_rng(3)
    r, _ = model.sample(0, rng.random((100000, 3)), channel=1)
    edges = np.concatenate([np.quantile(r, np.linspace(0, 1, 31))[:-1], [np.inf]])
    edges[0] = 0
    cdf = burley_energy_within(edges, 0.6, 1.0) / 0.6
    expected = np.diff(cdf) * r.size
    chi2 = ((np.histogram(r, edges)[0] - expected) ** 2 / expected).sum()
    assert stats.chi2.sf(chi2, 29) > 1e-3
    rad = model.energy_radius(0.999)
    assert burley_energy_within(rad[0], 0.4, 0.5) == pytest.approx(0.999 * 0.4, rel=1e-9)


def test_reduction_in_blocks_is_the_reduction_at_once(monkeypatch):
    """A scan's millions of profiles go through the reduction in blocks (bounded memory): the same
    numbers as all at once, whatever the block."""
    from translucency.model import burley

    rng = np.random.default_rng(5)
    c, d = rng.uniform(0.1, 1.0, (1000, 3, 3)), -rng.uniform(0.5, 5.0, (1000, 3, 3))
    whole = burley.burley_of_exponentials(c, d)
    monkeypatch.setattr(burley, "BURLEY_BLOCK", 7)
    for a, b in zip(whole, burley.burley_of_exponentials(c, d)):
        assert a.shape == (1000, 3)
        np.testing.assert_array_equal(a, b)
