"""Variable-projection fit of a radial sum of exponentials."""

import numpy as np
import pytest

from translucency import TranslucencyError
from translucency.fit import fit_burley_profile, fit_exponential_profile
from translucency.model import MATERIALS, burley_R, dipole_R_d


def test_recovers_three_terms():
    r = np.linspace(0.05, 15, 300)
    c_true, d_true = np.array([2.0, 0.2, 0.01]), np.array([-6.0, -1.2, -0.25])
    y = np.exp(np.outer(r, d_true)) @ c_true
    fit = fit_exponential_profile(r, y, 3)
    np.testing.assert_allclose(fit.c, c_true, rtol=1e-5)
    np.testing.assert_allclose(fit.d, d_true, rtol=1e-5)
    assert fit.rel_l2 < 1e-8


def test_dipole_fit_is_close_and_physical():
    m = MATERIALS["marble"]
    r = np.linspace(0.05, 20, 400)
    y = dipole_R_d(r, m.sigma_a[1], m.sigma_s_prime[1], 1.3)
    fit = fit_exponential_profile(r, y, 3)
    assert (fit.d < 0).all() and (fit.c >= 0).all()
    assert np.all(np.diff(fit.d) > 0)  # sorted steepest first
    assert fit.rel_l2 < 0.06
    # more terms never fit worse
    assert fit_exponential_profile(r, y, 4).rel_l2 <= fit.rel_l2 + 1e-9


def test_burley_fit_recovers():
    r = np.linspace(0.05, 10, 200)
    A, s, err = fit_burley_profile(r, burley_R(r, 0.55, 0.8))
    assert A == pytest.approx(0.55, rel=1e-6) and s == pytest.approx(0.8, rel=1e-6) and err < 1e-8


def test_bad_input():
    r = np.linspace(0, 1, 10)
    with pytest.raises(TranslucencyError, match="needs y > 0"):
        fit_exponential_profile(r, np.zeros(10))
    with pytest.raises(TranslucencyError, match="cannot determine"):
        fit_exponential_profile(r[:4], np.ones(4), 3)
    with pytest.raises(TranslucencyError, match="y: expected shape"):
        fit_exponential_profile(r, np.ones(9))
