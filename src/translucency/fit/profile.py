r"""Least-squares fit of a sum of exponentials to a radial profile.

Given samples :math:`y_j \approx R(r_j)` of a rotationally symmetric profile,
find :math:`c_k \ge 0` and :math:`d_k < 0` minimising the *relative* error

.. math:: \sum_j \Bigl(\frac{\sum_k c_k e^{d_k r_j} - y_j}{y_j}\Bigr)^2 ,

so that values spread over orders of magnitude count alike.  The problem is
separable (variable projection): for fixed exponents the amplitudes solve a
non-negative linear least-squares problem, so the outer search runs over the
n decay rates :math:`a_k = -d_k` alone, parametrised as :math:`\log a_k`.
Several starts spread over the rates the samples can resolve; the best wins.
Terms come out sorted by decreasing rate (steepest first) so that parameters
are identifiable.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares, nnls

from .._validate import TranslucencyError, as_float_array
from ..model.burley import burley_R
from ..model.dipole import dipole_R_d
from .families import FAMILIES


@dataclass(frozen=True)
class ProfileFit:
    """Result of :func:`fit_exponential_profile`.

    Attributes
    ----------
    c : ndarray, shape (n,)
        Amplitudes in the units of y (mm⁻² for R_d).
    d : ndarray, shape (n,)
        Exponents in mm⁻¹, all < 0, sorted from steepest to flattest.
    rel_l2 : float
        Relative L2 error :math:`\\|f - y\\| / \\|y\\|` with the fit's weights.

    Examples
    --------
    >>> fit = ProfileFit(c=np.array([0.5, 0.05]), d=np.array([-3.0, -0.4]), rel_l2=0.0)
    >>> float(fit(0.0)), round(float(fit(1.0)), 6)   # Σ c; 0.5 e⁻³ + 0.05 e^-0.4
    (0.55, 0.05841)
    >>> round(float(2 * np.pi * np.sum(fit.c / fit.d**2)), 4)   # its total 2π Σ c/d², dimensionless
    2.3126
    """

    c: np.ndarray
    d: np.ndarray
    rel_l2: float

    def __call__(self, r) -> np.ndarray:
        """Evaluate :math:`\\sum_k c_k e^{d_k r}`."""
        r = np.asarray(r, dtype=float)
        return np.exp(r[..., None] * self.d) @ self.c


def _amplitudes(a: np.ndarray, r: np.ndarray, y: np.ndarray, w: np.ndarray):
    """Projected problem: NNLS amplitudes for rates a and the weighted residual."""
    basis = np.exp(-np.outer(r, a))
    c, _ = nnls(basis * w[:, None], y * w)
    return c, (basis @ c - y) * w


def fit_exponential_profile(r, y, n_terms: int = 3, *, weights=None, n_starts: int = 4) -> ProfileFit:
    """Fit :math:`\\sum_{k=1}^n c_k e^{d_k r}` to samples of a radial profile.

    Parameters
    ----------
    r : array_like, shape (J,)
        Distances in mm (>= 0).
    y : array_like, shape (J,)
        Profile values (> 0 where weights are not given).
    n_terms : int
        Number of exponential terms n (the paper uses 3).
    weights : array_like, shape (J,), optional
        Residual weights; default ``1 / y`` (relative least squares).
    n_starts : int
        Number of starting points for the rates.

    Returns
    -------
    ProfileFit

    Examples
    --------
    >>> r = np.linspace(0.1, 10, 200)
    >>> fit = fit_exponential_profile(r, 0.5 * np.exp(-3 * r) + 0.05 * np.exp(-0.4 * r), 2)
    >>> fit.d.round(6)
    array([-3. , -0.4])
    """
    r = as_float_array("r", r, ndim=1)
    y = as_float_array("y", y, shape=r.shape)
    if n_terms < 1:
        raise TranslucencyError(f"n_terms: must be >= 1, got {n_terms}")
    if r.size < 2 * n_terms:
        raise TranslucencyError(f"r: {r.size} samples cannot determine {2 * n_terms} parameters")
    if weights is None:
        if not (y > 0).all():
            raise TranslucencyError("y: relative least squares needs y > 0; pass explicit weights")
        w = 1.0 / y
    else:
        w = as_float_array("weights", weights, shape=r.shape)

    # rates the samples can resolve: from half over the sampled range (a slower decay
    # is indistinguishable from a constant and would inflate 2π Σ c/d²) to ~1 over the spacing
    r_span = max(r.max() - r.min(), 1e-6)
    dr = max(np.min(np.diff(np.unique(r))) if r.size > 1 else r_span, 1e-6)
    lo, hi = np.log(0.5 / r_span), np.log(2.0 / dr)

    def residual(log_a):
        return _amplitudes(np.exp(log_a), r, y, w)[1]

    best = None
    for start in range(n_starts):
        # spread the initial rates geometrically, shifted a little per start
        frac = (np.arange(n_terms) + 0.5 + 0.25 * (start - (n_starts - 1) / 2) / max(n_starts, 1)) / n_terms
        x0 = lo + (hi - lo) * np.clip(frac, 0.05, 0.95) * 0.8
        sol = least_squares(residual, x0, bounds=(lo, hi + 2.0), method="trf")
        if best is None or sol.cost < best.cost:
            best = sol
    a = np.exp(best.x)
    c, res = _amplitudes(a, r, y, w)
    order = np.argsort(-a)
    rel = float(np.linalg.norm(res) / np.linalg.norm(y * w))
    return ProfileFit(c=c[order], d=-a[order], rel_l2=rel)


def fit_burley_profile(r, y, *, A0: float = 0.5, s0: float = 1.0) -> tuple[float, float, float]:
    """Fit Christensen–Burley's :math:`A s (e^{-sr} + e^{-sr/3})/(8\\pi r)` to a profile.

    Relative least squares over :math:`\\log A` and :math:`\\log s`.

    Returns
    -------
    A, s, rel_l2 : float
        Albedo, shape parameter (mm⁻¹) and relative L2 error.

    Examples
    --------
    >>> from translucency.model import burley_R
    >>> r = np.linspace(0.1, 10, 100)
    >>> [round(v, 6) for v in fit_burley_profile(r, burley_R(r, 0.7, 1.5))[:2]]
    [0.7, 1.5]
    """
    return _fit_positive_params(lambda r, p: burley_R(r, p[0], p[1]), r, y, (A0, s0))


def fit_dipole_profile(r, y, eta: float = 1.3, *, sigma_a0: float = 0.01, sigma_s_prime0: float = 1.0):
    """Fit Jensen's dipole to a radial profile: σ_a and σ_s' (mm⁻¹) free, η fixed.

    Relative least squares over :math:`\\log\\sigma_a, \\log\\sigma_s'` — how
    Jensen et al. 2001 obtain per-point dipole coefficients from a measurement.

    Returns
    -------
    sigma_a, sigma_s_prime, rel_l2 : float

    Examples
    --------
    >>> from translucency.model import dipole_R_d
    >>> r = np.linspace(0.2, 8, 80)
    >>> [round(v, 5) for v in fit_dipole_profile(r, dipole_R_d(r, 0.004, 2.6, 1.3))[:2]]
    [0.004, 2.6]
    """
    return _fit_positive_params(lambda r, p: dipole_R_d(r, p[0], p[1], eta), r, y, (sigma_a0, sigma_s_prime0))


def fit_pbd_profile(r, y, eta: float = 1.3, *, kind: str = "pbd", sigma_a0: float = 0.01, sigma_s_prime0=1.0):
    """Fit photon beam diffusion (``kind="pbd"``) or the directional dipole at normal incidence
    (``"ddipole"``) to a radial profile: σ_a and σ_s' (mm⁻¹) free, η fixed; relative least squares.

    Returns
    -------
    sigma_a, sigma_s_prime, rel_l2 : float

    Examples
    --------
    >>> from translucency.model import pbd_R_d
    >>> r = np.linspace(0.2, 8, 40)
    >>> [round(v, 4) for v in fit_pbd_profile(r, pbd_R_d(r, 0.004, 2.6, 1.3))[:2]]
    [0.004, 2.6]
    """
    if kind not in ("pbd", "ddipole"):
        raise TranslucencyError(f"kind: expected 'pbd' or 'ddipole', got {kind!r}")
    R = FAMILIES[kind].R_d  # the family's R_d(r; σ_a, σ_s', η)
    return _fit_positive_params(lambda r, p: R(r, p[0], p[1], eta), r, y, (sigma_a0, sigma_s_prime0))


def _fit_positive_params(profile, r, y, x0) -> tuple[float, ...]:
    """Relative least squares of ``profile(r, params)`` to y over the logs of positive params.

    Returns the parameters followed by the rms relative error.
    """
    r = as_float_array("r", r, ndim=1)
    y = as_float_array("y", y, shape=r.shape)
    if not (y > 0).all():
        raise TranslucencyError("y: relative least squares needs y > 0")

    def residual(log_p):
        return profile(r, np.exp(log_p)) / y - 1.0

    sol = least_squares(residual, np.log(np.asarray(x0, dtype=float)), method="lm")
    return (*(float(v) for v in np.exp(sol.x)), float(np.linalg.norm(sol.fun) / np.sqrt(r.size)))
