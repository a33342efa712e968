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
* :class:`FromViews` — γ tabulated over directions (cells of μ and of the azimuth from the direction
  away from the hit) per band of distance from the hit and channel, **estimated from the photographs
  themselves**: a vertex seen by several cameras sees one exitance through several cells of the
  table, so the table (normalised) and the exitances are fitted jointly (:func:`fit_from_views`).  A
  linear law in μ and s was tried first and dropped: near the hit the light leaves strongly peaked
  away from it (on the skin sphere, 1.5 mm from the hit, πL/M is 3.6 seen face-on leaning away from the
  hit, 0.5 seen from the side and 0.3 leaning towards it: measured by photon walks and volpath alike).
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
    """The factor γ(μ, s, r) = π L / M of the exit (module notes)."""

    name: str
    #: whether γ depends on the slant and the distance from the hit (else only on μ)
    needs_direction = False

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
        g = exit_factor(np.asarray(mu, dtype=np.float64), self.eta)
        return np.repeat(g[..., None], 3, axis=-1)

    def describe(self) -> dict:
        return {"law": self.name, "eta": float(self.eta)}


#: the table of :class:`FromViews`: cells in μ (uniform) and in the azimuth φ from the direction away from
#: the hit (uniform over [0°, 180°]; the law is mirror-symmetric about the plane through the hit)
MU_CELLS, PHI_CELLS = 4, 4


def _cells(mu, s) -> np.ndarray:
    """The table cell (flat index) of directions of cosine ``mu`` and slant ``s``."""
    mu = np.clip(np.asarray(mu, dtype=np.float64), 0.0, 1.0)
    sin = np.sqrt(np.maximum(1.0 - mu * mu, 1e-12))
    phi = np.arccos(np.clip(np.asarray(s, dtype=np.float64) / sin, -1.0, 1.0))
    i = np.minimum((mu * MU_CELLS).astype(np.int64), MU_CELLS - 1)
    j = np.minimum((phi / np.pi * PHI_CELLS).astype(np.int64), PHI_CELLS - 1)
    return i * PHI_CELLS + j


def cell_weights() -> np.ndarray:
    r""":math:`q_k = \int_{\text{cell } k} \mu\, d\omega` over the hemisphere (both mirror halves), so that
    :math:`\sum_k \gamma_k q_k = \pi` is the law's normalisation."""
    mu = np.linspace(0, 1, MU_CELLS + 1)
    q_mu = 0.5 * np.diff(mu**2)  # ∫ μ dμ per μ cell
    q_phi = np.full(PHI_CELLS, 2 * np.pi / PHI_CELLS)  # both halves: 2 × (π / cells)
    return np.outer(q_mu, q_phi).ravel()


@dataclass(frozen=True)
class FromViews(ExitLaw):
    r"""γ tabulated over directions (:data:`MU_CELLS` × :data:`PHI_CELLS` cells of μ and of the azimuth
    from the direction away from the hit) per distance band (:data:`BAND_EDGES_MM`) and channel, with
    :math:`\sum_k \gamma_k q_k = \pi` (:func:`cell_weights`).

    ``table`` has shape (bands, cells, 3); ``views`` says how many vertex views each band was estimated
    from.

    Examples
    --------
    >>> law = FromViews(np.ones((len(BAND_EDGES_MM), MU_CELLS * PHI_CELLS, 3)))   # Lambertian
    >>> float(law.factor(np.array([0.3]), np.array([0.1]), np.array([2.0]))[0, 0])
    1.0
    """

    table: np.ndarray
    views: tuple = ()
    name: str = "from-views"
    needs_direction = True

    def factor(self, mu, s, r):
        return np.asarray(self.table, dtype=np.float64)[
            np.clip(_band(r), 0, len(BAND_EDGES_MM) - 1), _cells(mu, s)
        ]

    def describe(self) -> dict:
        return {
            "law": self.name,
            "band_edges_mm": list(BAND_EDGES_MM),
            "cells": {"mu": MU_CELLS, "phi": PHI_CELLS},
            "table": np.round(np.asarray(self.table), 4).tolist(),
            "views": list(self.views),
        }


def _band(r) -> np.ndarray:
    return np.clip(np.searchsorted(BAND_EDGES_MM, np.asarray(r, dtype=np.float64), side="right") - 1, 0, None)


#: the fewest views a cell of the table is estimated from; one with fewer is extrapolated
MIN_CELL_VIEWS = 20


def _extrapolation(observed: np.ndarray) -> np.ndarray:
    """E (cells × cells): each cell's value as a combination of the observed cells' — itself where
    observed; below the lowest observed μ, linear in μ from the two cells above it (the grazing cells no
    view falls in); elsewhere the mean of its observed neighbours, or of every observed cell."""
    K = MU_CELLS * PHI_CELLS
    E = np.zeros((K, K))
    obs = observed.reshape(MU_CELLS, PHI_CELLS)
    for i in range(MU_CELLS):
        for j in range(PHI_CELLS):
            k = i * PHI_CELLS + j
            if obs[i, j]:
                E[k, k] = 1.0
            elif i + 2 < MU_CELLS and obs[i + 1, j] and obs[i + 2, j]:
                E[k, k + PHI_CELLS] = 2.0  # 2 γ(i+1) − γ(i+2): the line through the two cells above
                E[k, k + 2 * PHI_CELLS] = -1.0
            else:
                near = [
                    (a, c)
                    for a, c in ((i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1))
                    if 0 <= a < MU_CELLS and 0 <= c < PHI_CELLS and obs[a, c]
                ]
                cells = [a * PHI_CELLS + c for a, c in near] or list(np.flatnonzero(observed))
                E[k, cells] = 1.0 / len(cells)
    return E


def fit_from_views(L, var, mu, s, r, *, min_snr: float = 5.0, iterations: int = 40):
    r"""The tabulated law γ per distance band and channel from vertices seen by several cameras.

    Parameters
    ----------
    L, var : ndarray, shape (C, N, 3)
        Each camera's mean radiance over each vertex's cell (and its variance), NaN where the camera does
        not see the vertex.
    mu, s : ndarray, shape (C, N)
        The cosine of each camera's view to the vertex's normal, and its slant (module notes).
    r : ndarray, shape (N,)
        Each vertex's distance from its laser hit, mm.

    The views (above ``min_snr`` σ) of vertices seen by two cameras or more are fitted jointly with the
    vertices' exitances, :math:`\pi L_{vc} = M_v \gamma_{k(vc)}`: alternately the weighted least-squares
    :math:`M_v` for a fixed table, and the table for fixed M — linear least squares over the cells with
    :data:`MIN_CELL_VIEWS` views or more, the others extrapolated from them (:func:`_extrapolation`:
    linearly in μ below the grazing cut), under the normalisation :math:`\sum_k \gamma_k q_k = \pi`
    (a Lagrange constraint).  Weights :math:`1/(\mathrm{Var}\,L + (0.02 L)^2)`.  A band with fewer
    than :data:`MIN_PAIRS` such vertices takes its nearest estimated band's table.

    Returns
    -------
    FromViews
    """
    L, var, mu, s = (np.asarray(a, dtype=np.float64) for a in (L, var, mu, s))
    bands, K = len(BAND_EDGES_MM), MU_CELLS * PHI_CELLS
    band = np.clip(_band(r), 0, bands - 1)
    q = cell_weights()
    table = np.ones((bands, K, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        good = np.isfinite(L) & (L / np.sqrt(var) >= min_snr)
    views = good.all(axis=2)  # (C, N)
    multi = views.sum(axis=0) >= 2
    counts = np.bincount(band[multi], minlength=bands)
    cells = _cells(mu, s)  # (C, N)
    for b in range(bands):
        m = multi & (band == b)
        if m.sum() < MIN_PAIRS:
            continue
        v = views[:, m]
        k = cells[:, m]
        observed = np.bincount(k[v], minlength=K) >= MIN_CELL_VIEWS
        if not observed.any():
            continue
        E = _extrapolation(observed)[:, observed]  # (K, n_obs): the table from its observed cells
        qo = q @ E
        for ch in range(3):
            y = np.where(v, np.pi * L[:, m, ch], 0.0)
            Lv = np.where(v, L[:, m, ch], 0.0)
            w = np.where(
                v, 1.0 / (np.pi**2 * (np.nan_to_num(var[:, m, ch]) + (0.02 * Lv) ** 2) + 1e-300), 0.0
            )
            g = np.ones(K) * np.pi / q.sum()
            for _ in range(iterations):
                gv = g[k]
                M = (w * gv * y).sum(0) / np.maximum((w * gv * gv).sum(0), 1e-300)  # (n,)
                # the observed cells for fixed M: Σ w (y − M γ_k)², subject to qᵀ E γ_o = π
                Mv = np.broadcast_to(M, k.shape)
                sel = v & observed[k]
                X = np.zeros((sel.sum(), observed.sum()))
                X[np.arange(sel.sum()), np.searchsorted(np.flatnonzero(observed), k[sel])] = Mv[sel]
                ww = w[sel]
                A = np.zeros((observed.sum() + 1,) * 2)
                A[:-1, :-1] = (X * ww[:, None]).T @ X
                A[:-1, -1] = A[-1, :-1] = qo
                rhs = np.r_[(X * ww[:, None]).T @ y[sel], np.pi]
                go = np.linalg.lstsq(A, rhs, rcond=None)[0][:-1]
                g = np.maximum(E @ go, 0.02)
                g *= np.pi / (q @ g)
            table[b, :, ch] = g
    ok = counts >= MIN_PAIRS
    if not ok.any():
        raise TranslucencyError(
            f"exit law: fewer than {MIN_PAIRS} vertices are seen well by two cameras in any band of "
            "distance; choose exit_law='lambertian' or 'dielectric', or add views"
        )
    idx = np.arange(bands)
    nearest = np.array([idx[ok][np.argmin(np.abs(idx[ok] - i))] for i in idx])
    return FromViews(table[nearest], tuple(int(c) for c in counts))


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
