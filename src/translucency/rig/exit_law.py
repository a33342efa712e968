r"""From radiance seen by a camera to exitance: the angular law of light leaving the object.

A camera measures the radiance :math:`L(y, \omega_o)` that leaves a surface point y towards it; the
data set holds the exitance :math:`M(y) = \int L \cos\theta_o\, d\omega`.  The two are related by
the exit's angular law, written here as the factor

.. math:: \gamma(\mu, s, r) = \frac{\pi L}{M}, \qquad \int_{H^2} \gamma\, \mu\, d\omega = \pi,

of the cosine :math:`\mu = \cos\theta_o` to the surface normal and the *slant*
:math:`s = \omega_o\cdot\hat t` (:math:`\hat t` the unit tangent pointing away from the laser's hit),
varying with the distance r from the hit; the import divides :math:`\pi L` by it.  It is *not* 1 (a
Lambertian exit) through an index-matched boundary.  Photon walks on a 6 mm skin sphere
(``homogeneous:skin1``) give, azimuthally averaged, :math:`\gamma \approx 1` within 2 mm of the hit
and :math:`\gamma(1) \approx 1.2`, :math:`\gamma(0.1) \approx 0.2` at 4–8 mm (the Milne problem's
law); and light leaves leaning *away* from the hit — seen along +z from 1–2 mm off the pole, where
the normal is only 10–20° from +z (so s ≈ −0.3), πL is 0.61 M.  So π × radiance is off by up to
±40 % depending on the view.  Three laws, one object each behind :class:`ExitLaw`:

* :class:`Lambertian` — γ = 1 (a rough, white-diffusing surface, or for comparison only);
* :class:`Dielectric` — :math:`\gamma = F_t(\mu)/(1 - F_{dr,e})` for a smooth boundary of index η,
  the law the renderer draws with (:mod:`translucency.model.boundary`);
* :class:`FromViews` — :math:`\gamma = (1 + \beta_b\mu + \kappa_b s)/(1 + 2\beta_b/3)` with one
  (β, κ) per band b of distance from the hit and channel (the κ term integrates to zero against μ, so
  the normalisation holds), **estimated from the photographs themselves**: a vertex seen by two
  cameras gives :math:`L_1 (1 + \beta\mu_2 + \kappa s_2) = L_2 (1 + \beta\mu_1 + \kappa s_1)`,
  so each band's pair is a weighted least-squares fit jointly with the vertices' M (:func:`fit_from_views`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError
from ..model.boundary import exit_factor

#: distance bands (mm from the laser's hit) of :class:`FromViews`, the last one open
BAND_EDGES_MM = (0.0, 1.0, 2.0, 4.0, 8.0, 16.0)

#: the fewest pairs of views a band's β is estimated from; a band with fewer takes its neighbour's
MIN_PAIRS = 12


class ExitLaw(ABC):
    """The factor γ(μ, r) = π L / M of the exit (module notes)."""

    name: str

    @abstractmethod
    def factor(self, mu: np.ndarray, s: np.ndarray, r: np.ndarray) -> np.ndarray:
        """γ (..., 3) at cosines ``mu`` (to the outward normal), slants ``s`` (to the tangent pointing away
        from the hit) and distances ``r`` (mm from the hit), all of one shape (...)."""

    def describe(self) -> dict:
        return {"law": self.name}


class Lambertian(ExitLaw):
    """γ = 1: π × radiance is the exitance."""

    name = "lambertian"

    def factor(self, mu, s, r):
        return np.ones(np.shape(mu) + (3,))


@dataclass(frozen=True)
class Dielectric(ExitLaw):
    """γ = F_t(μ)/(1 − F_dr,e) of a smooth boundary of relative index ``eta`` (diffusion approximation).

    Examples
    --------
    >>> law = Dielectric(1.3)
    >>> mu = (np.arange(2000) + 0.5) / 2000
    >>> round(float(2 * np.mean(law.factor(mu, 0 * mu, 0 * mu)[:, 0] * mu)), 4)   # 2 ∫ γ μ dμ = 1
    1.0
    """

    eta: float
    name: str = "dielectric"

    def factor(self, mu, s, r):
        shape = np.broadcast(np.asarray(mu), np.asarray(s), np.asarray(r)).shape
        mu = np.broadcast_to(np.asarray(mu, dtype=np.float64), shape)
        return np.repeat(exit_factor(mu, self.eta)[..., None], 3, axis=-1)  # one law for every channel

    def describe(self) -> dict:
        return {"law": self.name, "eta": float(self.eta)}


@dataclass(frozen=True)
class FromViews(ExitLaw):
    """γ = (1 + β μ + κ s)/(1 + 2β/3) with (β, κ) per distance band (:data:`BAND_EDGES_MM`) and channel.

    ``beta`` and ``kappa`` have shape (bands, 3); ``pairs`` says how many pairs of views each band was
    estimated from.

    Examples
    --------
    >>> law = FromViews(np.full((len(BAND_EDGES_MM), 3), 1.5), np.full((len(BAND_EDGES_MM), 3), 0.3))
    >>> mu = (np.arange(2000) + 0.5) / 2000
    >>> round(float(2 * np.mean(law.factor(mu, 0 * mu, 3.0 + 0 * mu)[:, 0] * mu)), 4)
    1.0
    """

    beta: np.ndarray
    kappa: np.ndarray
    pairs: tuple = ()
    name: str = "from-views"

    def factor(self, mu, s, r):
        mu, s = (np.asarray(a, dtype=np.float64)[..., None] for a in (mu, s))
        band = _band(r)
        b = np.asarray(self.beta, dtype=np.float64)[band]
        k = np.asarray(self.kappa, dtype=np.float64)[band]
        return np.maximum(1.0 + b * mu + k * s, 0.05) / (1.0 + 2.0 * b / 3.0)

    def describe(self) -> dict:
        return {
            "law": self.name,
            "band_edges_mm": list(BAND_EDGES_MM),
            "beta": np.round(np.asarray(self.beta), 4).tolist(),
            "kappa": np.round(np.asarray(self.kappa), 4).tolist(),
            "pairs": list(self.pairs),
        }


def _band(r) -> np.ndarray:
    return np.clip(np.searchsorted(BAND_EDGES_MM, np.asarray(r, dtype=np.float64), side="right") - 1, 0, None)


def fit_from_views(L, var, mu, s, r, *, min_snr: float = 5.0, iterations: int = 30) -> FromViews:
    r"""(β, κ) per distance band and channel from vertices seen by several cameras.

    Parameters
    ----------
    L, var : ndarray, shape (C, N, 3)
        Each camera's mean radiance over each vertex's cell (and its variance), NaN where the camera does
        not see the vertex.
    mu, s : ndarray, shape (C, N)
        The cosine of each camera's view to the vertex's normal, and its slant (module notes).
    r : ndarray, shape (N,)
        Each vertex's distance from its laser hit, mm.

    The views of a vertex seen by two cameras or more, each above ``min_snr`` σ, are fitted jointly with
    the vertex's exitance: :math:`\pi L_{vc} = M_v \gamma(\mu_{vc}, s_{vc})`, by alternating the
    weighted least-squares :math:`M_v` for fixed (β, κ) and a Gauss–Newton step of
    :math:`\pi L = M \gamma(\mu, s; \beta, \kappa)` in (β, κ) for fixed M (weights
    :math:`1/(\mathrm{Var}\,L + (0.02 L)^2)`), clipped to β ∈ [−0.9, 10], |κ| ≤ 1.5.  A band with fewer
    than :data:`MIN_PAIRS` such vertices takes its nearest estimated band's values.
    """
    L, var, mu, s = (np.asarray(a, dtype=np.float64) for a in (L, var, mu, s))
    bands = len(BAND_EDGES_MM)
    band = np.clip(_band(r), 0, bands - 1)
    beta = np.zeros((bands, 3))
    kappa = np.zeros((bands, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        good = np.isfinite(L) & (L / np.sqrt(var) >= min_snr)  # (C, N, 3)
    views = good.all(axis=2)  # (C, N): a view good in every channel
    multi = views.sum(axis=0) >= 2
    counts = np.bincount(band[multi], minlength=bands)
    for b in range(bands):
        m = multi & (band == b)
        if m.sum() < MIN_PAIRS:
            continue
        v = views[:, m]  # (C, n)
        for ch in range(3):
            Lc = np.where(v, L[:, m, ch], 0.0)
            w = np.where(v, 1.0 / (np.nan_to_num(var[:, m, ch]) + (0.02 * Lc) ** 2 + 1e-300), 0.0)
            mc, sc = mu[:, m], s[:, m]
            be, ka = 0.0, 0.0
            for _ in range(iterations):
                d = 1 + 2 * be / 3
                g = np.maximum(1 + be * mc + ka * sc, 0.05) / d
                M = np.pi * (w * g * Lc).sum(0) / np.maximum((w * g * g).sum(0), 1e-300)  # (n,)
                # a Gauss–Newton step of the residual π L − M γ(μ, s; β, κ) in (β, κ): its Jacobian holds
                # the model only (the measured L in a regressor would bias β towards 0 as noise grows)
                e = (np.pi * Lc - M * g)[v]
                j1 = (M * (mc - 2 * g / 3) / d)[v]  # ∂(M γ)/∂β
                j2 = (M * sc / d)[v]  # ∂(M γ)/∂κ
                ww = w[v]
                A = np.array([[ww @ (j1 * j1), ww @ (j1 * j2)], [ww @ (j1 * j2), ww @ (j2 * j2)]])
                try:
                    step = np.linalg.solve(A, np.array([ww @ (j1 * e), ww @ (j2 * e)]))
                except np.linalg.LinAlgError:
                    break
                be, ka = float(np.clip(be + step[0], -0.9, 10.0)), float(np.clip(ka + step[1], -1.5, 1.5))
            beta[b, ch], kappa[b, ch] = be, ka
    ok = counts >= MIN_PAIRS
    if not ok.any():
        raise TranslucencyError(
            f"exit law: fewer than {MIN_PAIRS} vertices are seen well by two cameras in any band of "
            "distance; choose exit_law='lambertian' or 'dielectric', or add views"
        )
    idx = np.arange(bands)
    nearest = np.array([idx[ok][np.argmin(np.abs(idx[ok] - i))] for i in idx])
    return FromViews(beta[nearest], kappa[nearest], tuple(int(c) for c in counts))


def law_named(name: str, eta: float = 1.0) -> ExitLaw | None:
    """The law a rig file names: ``"lambertian"``, ``"dielectric"`` (needs η ≠ 1) or ``"from-views"`` (None:
    it is estimated from the photographs)."""
    if name == "lambertian":
        return Lambertian()
    if name == "dielectric":
        if eta == 1.0:
            raise TranslucencyError("exit_law: 'dielectric' needs the boundary's eta > 1")
        return Dielectric(float(eta))
    if name == "from-views":
        return None
    raise TranslucencyError(f"exit_law: one of lambertian, dielectric, from-views; got {name!r}")


__all__ = ["ExitLaw", "Lambertian", "Dielectric", "FromViews", "fit_from_views", "law_named", "BAND_EDGES_MM"]
