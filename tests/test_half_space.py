"""The half-space profile table (``model/half_space.py``, the near-peak model of an index-matched object's
import) against independent truths: iadpython's adding-doubling for its total reflectance, energy
conservation, and the single-scattering closed form for its near peak."""

import numpy as np
import pytest
from scipy.integrate import quad

from translucency.model.half_space import albedo_range, half_space_R_d, half_space_total

iad = pytest.importorskip("iadpython")


@pytest.mark.parametrize("albedo", [0.4, 0.8, 0.95, 0.99])
def test_the_tables_total_is_the_adding_doubling_half_space(albedo):
    """The table's photons that came back, against iadpython's UR1 for a slab thick enough to be a
    half-space (200 mean free paths), index-matched, isotropic, at normal incidence: within 0.5 %
    (2 M photons: standard errors 3e-4); and the interpolated profile integrates to it within 1 %."""
    ur1 = float(
        iad.Sample(a=albedo, b=200.0, g=0.0, d=1.0, n=1.0, n_above=1.0, n_below=1.0, quad_pts=16).rt()[0]
    )
    assert abs(half_space_total(albedo) - ur1) < 0.005 * ur1 + 1e-3, (half_space_total(albedo), ur1)
    r = np.concatenate([np.linspace(0, 0.01, 2001)[1:], np.geomspace(0.01, 400.0, 100_000)])
    integral = np.trapezoid(2 * np.pi * r * half_space_R_d(r, 1.0, albedo), r)
    assert abs(integral / ur1 - 1) < 0.01, (integral, ur1)


def test_the_near_peak_is_the_first_scattering_where_it_dominates():
    r"""At low albedo the light that comes back near the beam has scattered once.  Single scattering of a
    normal beam in an index-matched isotropic half-space (σ_t = 1):
    :math:`R^{(1)}(r) = \frac{\alpha}{4\pi}\int_0^\infty e^{-z} e^{-d} \frac{z}{d^3}\,dz`, d = √(r² + z²),
    the exit cosine z/d.  The table, which holds every order, lies above it by less than the higher
    orders add (at α = 0.2, 0–16 % above it at 0.05–0.5 mean free paths, the excess growing with r)."""
    albedo = 0.2

    def single(r):
        return (
            albedo
            / (4 * np.pi)
            * quad(lambda z: np.exp(-z - np.hypot(r, z)) * z / np.hypot(r, z) ** 3, 0, 60)[0]
        )

    ratios = [half_space_R_d(np.array([r]), 1.0, albedo)[0] / single(r) for r in (0.05, 0.1, 0.2, 0.5)]
    assert all(0.97 < q < 1.16 for q in ratios), ratios
    assert ratios[-1] > ratios[0]  # the higher orders matter more away from the beam


def test_scale_and_energy_conservation():
    """R_d(r; σ_t, α) = σ_t² f(σ_t r; α); no albedo of the table returns more light than came in."""
    r = np.geomspace(0.01, 20, 50)
    assert np.allclose(half_space_R_d(r, 2.5, 0.9), 2.5**2 * half_space_R_d(2.5 * r, 1.0, 0.9))
    lo, hi = albedo_range()
    assert 0 < lo < hi < 1
    assert all(0 < half_space_total(a) < 1 for a in np.linspace(lo, hi, 9))
    # the profile decays with distance (within the tally's noise at the fine bins)
    p = half_space_R_d(np.geomspace(0.05, 30, 40), 1.0, 0.95)
    assert (np.diff(p) < 0.02 * p[:-1]).all()
