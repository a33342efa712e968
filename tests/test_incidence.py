"""The incidence law (translucency.model.incidence): Chandrasekhar's H-function and plane albedo against
closed forms, iadpython's adding-doubling and a plain Monte Carlo random walk; the renderer's effective
irradiance against its quadrature."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from translucency import TranslucencyError
from translucency.mitsuba import mesh_scene
from translucency.model.incidence import (
    HalfSpaceIncidence,
    NormalIncidence,
    chandrasekhar_h,
    cosine_mean,
    incidence_factor,
    incidence_law,
    plane_albedo,
)
from translucency.render import DirectionalLight, EnvironmentLight
from translucency.transport import vertex_irradiance


def _gauss(n=64):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


@pytest.mark.parametrize("a", [0.1, 0.5, 0.9, 0.99, 0.9999, 1.0])
def test_h_function_closed_forms(a):
    """H(0) = 1, and the zeroth moment ∫₀¹ H dμ = (2/a)(1 − √(1 − a)) (Chandrasekhar 1960, V.(26))."""
    x, w = _gauss()
    assert chandrasekhar_h(0.0, a) == pytest.approx(1.0, abs=1e-12)
    assert np.sum(w * chandrasekhar_h(x, a)) == pytest.approx(2.0 / a * (1.0 - np.sqrt(1.0 - a)), rel=2e-6)
    # H grows with μ and with a
    h = chandrasekhar_h(x, a)
    assert (np.diff(h) > 0).all() and (chandrasekhar_h(x, min(a + 0.05, 1.0)) >= h - 1e-12).all()


def test_conservative_h_is_chandrasekhars_table():
    """The conservative H(1) = 2.90781 (Chandrasekhar's Table XI); everything comes back: R(μ) = 1."""
    assert float(chandrasekhar_h(1.0, 1.0)) == pytest.approx(2.90781, abs=2e-5)
    np.testing.assert_allclose(plane_albedo(np.linspace(0, 1, 11), 1.0), 1.0, atol=1e-12)


@pytest.mark.parametrize("a", [0.3, 0.9, 0.958, 0.99])
def test_plane_albedo_matches_adding_doubling(a):
    """A thick index-matched slab in iadpython (an independent adding-doubling code): R(μ₀) for every one
    of its 32 incidence angles within 10⁻³, and the incidence factor within 10⁻³ as well."""
    iad = pytest.importorskip("iadpython")
    s = iad.Sample(a=a, b=1e4, g=0.0, n=1.0, n_above=1.0, n_below=1.0, quad_pts=32)
    R = s.rt_matrices()[0]
    R_mu = (R * s.twonuw[None, :]).sum(axis=1)  # total reflectance for light from each quadrature angle
    np.testing.assert_allclose(plane_albedo(s.nu, a), R_mu, atol=1e-3)
    np.testing.assert_allclose(incidence_factor(s.nu, R_mu[-1]), R_mu / R_mu[-1], atol=1e-3)


def _random_walk(a: float, mu0: float, n: int, rng) -> tuple[float, float]:
    """Plain Monte Carlo of a half-space z > 0 (index-matched, isotropic, σ_t = 1): the fraction of photons
    that leave through z = 0, and its standard error."""
    z = -np.log(rng.random(n)) * mu0  # first collision depth
    weight = np.ones(n)
    out = np.zeros(n)
    alive = np.ones(n, bool)
    while alive.any():
        weight[alive] *= a  # survival: the albedo as a weight
        mu = rng.uniform(-1.0, 1.0, alive.sum())  # isotropic new direction
        step = -np.log(rng.random(alive.sum()))
        zn = z[alive] + mu * step
        escaped = zn < 0
        idx = np.flatnonzero(alive)
        out[idx[escaped]] = weight[idx[escaped]]
        z[idx] = zn
        alive[idx[escaped]] = False
        alive &= weight > 1e-4  # the rest carries < 10⁻⁴ each
    return float(out.mean()), float(out.std() / np.sqrt(n))


@pytest.mark.parametrize("a, mu0", [(0.9, 1.0), (0.9, 0.2), (0.6, 0.5)])
def test_plane_albedo_matches_a_random_walk(a, mu0):
    """The plane albedo against a plain scalar Monte Carlo of the same half-space, within 4 standard errors
    (plus the walk's 10⁻⁴ cut-off)."""
    R, se = _random_walk(a, mu0, 200_000, np.random.default_rng(7))
    assert abs(float(plane_albedo(mu0, a)) - R) < 4 * se + 1e-3


def test_incidence_factor_bounds_and_monotone():
    """F(1) = 1; F grows toward grazing; R₁ F ≤ 1 (reflectance bounded); μ ≤ 0 gives 0."""
    mu = np.linspace(0.02, 1.0, 50)
    for R1 in (0.05, 0.3, 0.56, 0.9, 0.99):
        F = incidence_factor(mu, R1)
        assert F[-1] == pytest.approx(1.0, abs=1e-6)
        assert (np.diff(F) < 1e-9).all()
        assert (R1 * F <= 1.0 + 1e-6).all()
    assert (incidence_factor([0.0, -0.5], 0.5) == 0).all()


def test_effective_irradiance_is_the_quadrature_of_the_law():
    """On a ball (convex: the whole sky from every vertex) the constant sky's effective irradiance is
    π L · 2∫₀¹ F(μ) μ dμ per vertex and channel, estimated with cosine-weighted rays; a directional light
    gives E cos θ · F(cos θ) exactly; the normal law changes nothing."""
    ball = trimesh.creation.icosphere(3, radius=5.0)
    scene = mesh_scene(ball)
    R1 = np.tile([0.73, 0.56, 0.47], (len(ball.vertices), 1))  # skin's three channels
    law = HalfSpaceIncidence(R1)
    x, w = _gauss()
    expected = np.pi * 0.3 * np.array([2 * np.sum(w * x * incidence_factor(x, r)) for r in R1[0]])
    sky = vertex_irradiance(ball, scene, EnvironmentLight(0.3, samples=512), incidence=law)
    assert sky.shape == (len(ball.vertices), 3)
    # 512 rays per vertex: the per-vertex mean is within 1.5 %, the mean over vertices within 0.2 %
    np.testing.assert_allclose(sky.mean(axis=0), expected, rtol=2e-3)
    np.testing.assert_allclose(sky, np.broadcast_to(expected, sky.shape), rtol=0.03)
    assert expected[2] / (np.pi * 0.3) == pytest.approx(1.135, abs=0.01)  # blue: 13.5 % more than normal
    sun = DirectionalLight((0.0, 0.0, -1.0), 2.0)
    plain = vertex_irradiance(ball, scene, sun)
    lit = vertex_irradiance(ball, scene, sun, incidence=law)
    cos = ball.vertex_normals[:, 2]
    on = plain > 0
    np.testing.assert_allclose(lit[on], plain[on, None] * incidence_factor(cos[on, None], R1[on]), rtol=1e-9)
    assert (lit[~on] == 0).all()
    assert vertex_irradiance(ball, scene, sun, incidence=NormalIncidence()) == pytest.approx(plain)


def test_law_choice_and_bad_names():
    """A dielectric object or one without measured totals gets the normal law; an unknown name one line."""
    R1 = np.full((4, 3), 0.5)
    assert isinstance(incidence_law("half-space", R1, 1.0), HalfSpaceIncidence)
    assert isinstance(incidence_law("half-space", R1, 1.4), NormalIncidence)
    assert isinstance(incidence_law("half-space", None, 1.0), NormalIncidence)
    assert isinstance(incidence_law("normal", R1, 1.0), NormalIncidence)
    with pytest.raises(TranslucencyError, match="'oblique' is not one of half-space, half-space-in, normal"):
        incidence_law("oblique", R1)


def test_exit_side_is_reciprocal_and_keeps_the_exitance():
    """The exit factor F(μ_o)/⟨F⟩ integrates to 1 over the hemisphere (2∫ f μ dμ = 1: the exitance is kept),
    and under a uniform sky gives exactly the half-space's reflected radiance L R(μ_o) = L R₁ F(μ_o)
    (reciprocity); the irradiance-only ablation has no exit factor."""
    R1 = np.array([[0.73, 0.56, 0.47], [0.9, 0.3, 0.05]])
    law = HalfSpaceIncidence(R1)
    x, w = _gauss(96)
    f = np.stack([law.exit(np.full(2, mu)) for mu in x])  # (K, V, 3)
    np.testing.assert_allclose(2 * np.einsum("k,kvc->vc", w * x, f), 1.0, atol=2e-3)
    # under a uniform sky L: exitance M = R₁ · π L ⟨F⟩, so π L_out = M f must be π L R(μ_o)
    mu = np.array([0.9, 0.2])
    M = R1 * np.pi * cosine_mean(R1)
    a = [[float(_albedo_of(r)) for r in row] for row in R1]
    np.testing.assert_allclose(M * law.exit(mu) / np.pi, plane_albedo(mu[:, None], np.array(a)), rtol=3e-3)
    assert HalfSpaceIncidence(R1, both_ways=False).exit(mu) is None and NormalIncidence().exit(mu) is None
    assert incidence_law("half-space-in", R1).name == "half-space-in"


def _albedo_of(R1: float) -> float:
    """The albedo whose normal-incidence plane albedo is R1 (bisection on the closed form)."""
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(plane_albedo(1.0, mid)) < R1 else (lo, mid)
    return 0.5 * (lo + hi)


def test_wavefront_kernel_is_the_numpy_law():
    """The Dr.Jit lookup of a wavefront (each sample's vertex and cosine) against the NumPy law it mirrors,
    over albedos from dark to near-conservative and cosines from grazing to normal (single precision)."""
    from translucency.mitsuba import mitsuba

    mi = mitsuba()
    rng = np.random.default_rng(4)
    R1 = rng.uniform(0.005, 0.95, size=(50, 3))
    law = HalfSpaceIncidence(R1)
    v = rng.integers(0, 50, size=4000)
    mu = np.concatenate([rng.uniform(-0.2, 1.0, size=3996), [0.0, 1e-6, 1.0, -1.0]])
    expected = law.factor(mu[:, None].repeat(1, axis=1).T.repeat(50, axis=0))  # (50, N, 3): every vertex
    expected = expected[v, np.arange(len(v))]
    got = np.asarray(law.kernel()(mi.UInt32(v.astype(np.uint32)), mi.Float(mu.astype(np.float32)))).T
    assert np.allclose(got, expected, rtol=2e-5, atol=2e-6)
    assert (got[mu <= 0] == 0).all() and np.allclose(got[mu == 1.0], 1.0, atol=1e-5)
    assert NormalIncidence().kernel() is None
