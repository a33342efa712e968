"""w_l: partition of unity, non-negative, continuous across θ = 0/2π, each integrating to 2π/m."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.integrate import quad

from translucency.model import direction_weights
from translucency.model.directions import sample_direction_offset

angles = st.floats(min_value=-20.0, max_value=20.0, allow_nan=False)


@given(theta=angles, m=st.integers(min_value=1, max_value=16))
def test_partition_of_unity(theta, m):
    w = direction_weights(theta, m)
    assert w.shape == (m,)
    assert (w >= 0).all()
    assert w.sum() == pytest.approx(1.0, abs=1e-12)
    assert (w > 0).sum() <= 2  # at most the two nearest directions


@pytest.mark.parametrize("m", [2, 3, 8, 12])
def test_continuous_across_zero(m):
    eps = 1e-9
    np.testing.assert_allclose(direction_weights(2 * np.pi - eps, m), direction_weights(eps, m), atol=1e-7)
    np.testing.assert_allclose(direction_weights(-eps, m), direction_weights(eps, m), atol=1e-7)
    # a fine sweep has no jumps anywhere (Lipschitz constant m/2π per weight)
    theta = np.linspace(-0.5, 2 * np.pi + 0.5, 20001)
    jumps = np.abs(np.diff(direction_weights(theta, m), axis=0)).max()
    assert jumps <= m / (2 * np.pi) * (theta[1] - theta[0]) * 1.0001


@pytest.mark.parametrize("m", [1, 2, 8])
def test_each_weight_integrates_to_two_pi_over_m(m):
    for l in range(m):
        val = quad(
            lambda t, l=l: direction_weights(t, m)[l],
            0,
            2 * np.pi,
            points=np.linspace(0, 2 * np.pi, m + 1),
            limit=200,
        )[0]
        assert val == pytest.approx(2 * np.pi / m, rel=1e-9)


def test_weights_peak_at_their_direction():
    w = direction_weights(np.arange(8) * np.pi / 4, 8)
    np.testing.assert_allclose(w, np.eye(8), atol=1e-12)


@pytest.mark.parametrize("m", [2, 8])
def test_offset_sampler_is_the_hat(m):
    u = np.random.default_rng(1).random(200000)
    off = sample_direction_offset(u, m)
    delta = 2 * np.pi / m
    hist, edges = np.histogram(off, bins=20, range=(-delta, delta))
    centre = 0.5 * (edges[1:] + edges[:-1])
    expected = len(u) * (edges[1] - edges[0]) * (1 - np.abs(centre) / delta) / delta
    chi2 = ((hist - expected) ** 2 / expected).sum()
    assert chi2 < 45  # 20 bins: the 99.9 % quantile of χ²(19) is 43.8
