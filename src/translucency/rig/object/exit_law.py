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
±40 % depending on the view.  The laws, one object each behind :class:`ExitLaw`:

* :class:`Lambertian` — γ = 1 (a rough, white-diffusing surface, or for comparison only);
* :class:`Dielectric` — :math:`\gamma = F_t(\mu)/(1 - F_{dr,e})` for a smooth boundary of index η,
  the law the renderer draws with (:mod:`translucency.model.boundary`);
* :class:`FromViews` — :math:`\gamma = \pi (1 + a\mu) e^{\kappa s}/N(a, \kappa)`, a law peaked away
  from the hit (κ > 0) and tilted towards the normal (a > 0), normalised, with one (a, κ) per band of
  distance from the hit and channel, **estimated from the photographs themselves**: a vertex seen by
  several cameras sees one exitance through several directions, so (a, κ) and the exitances are fitted
  jointly (:func:`fit_from_views`, a grid search).  Tried and dropped: a law linear in μ and s (cannot
  hold the peak: near the hit, on the skin sphere 1.5 mm away, πL/M is 3.6 seen face-on leaning away
  from the hit, 0.5 from the side and 0.3 leaning towards it — photon walks and volpath alike), and a
  table over 4 × 4 cells of directions (too coarse for the peak: the true law tabulated so converts
  10–60 % off; and too many unknowns for a few views per vertex);
* :class:`Walked` — γ per cell and camera from photon walks on the scan at the material the near peak
  fitted to the same shot (:mod:`.walk_law`): the transport's own law where each camera sees it;
* :class:`Tabulated` — γ read from a photon tally's exit bins (``acquire mesh --exit-bins``,
  :mod:`translucency.angles`): per band of distance from the hit (:data:`TABLE_EDGES_MM`), polar bin and
  azimuthal sector about the away axis (two halves, s > 0 away from the hit and s < 0 back, unless the
  tally was made with more sectors), :math:`\gamma_b = \pi L_b / M`
  over the band's vertices; a rig file names it ``"tally:PATH"``.  Exact in the bins' mean, piecewise
  constant within them.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from ..._validate import TranslucencyError
from ...model.boundary import exit_factor

#: distance bands (mm from the laser's hit) of :class:`FromViews`, the last one open
BAND_EDGES_MM = (0.0, 2.0, 6.0)

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


class Walked(ExitLaw):
    """γ per cell and camera from photon walks on the scan at the material the near peak fitted to each shot
    (:class:`.walk_law.ShotWalkLaw`): the import converts each shot twice, first with π L (γ = 1 here)."""

    name = "walk"

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


def _normalisation(a, kappa) -> np.ndarray:
    r""":math:`N(a, \kappa) = \int_{H^2} (1 + a\mu)\, e^{\kappa s} \mu\, d\omega` with
    :math:`s = \sin\theta\cos\varphi`: :math:`2\pi \int_0^1 (1 + a\mu) I_0(\kappa\sqrt{1-\mu^2})
    \mu\, d\mu` (the azimuth's integral is the Bessel function I_0), by Gauss–Legendre in μ."""
    x, w = np.polynomial.legendre.leggauss(48)
    mu, wmu = (x + 1) / 2, w / 2
    a, kappa = np.asarray(a, dtype=np.float64), np.asarray(kappa, dtype=np.float64)
    i0 = np.i0(kappa[..., None] * np.sqrt(1 - mu**2))
    return 2 * np.pi * ((1 + a[..., None] * mu) * i0 * mu * wmu).sum(axis=-1)


@dataclass(frozen=True)
class FromViews(ExitLaw):
    r""":math:`\gamma = \pi (1 + a\mu)\, e^{\kappa s} / N(a, \kappa)` with (a, κ) per distance band
    (:data:`BAND_EDGES_MM`) and channel; N (:func:`_normalisation`) makes
    :math:`\int \gamma \mu\, d\omega = \pi`.  κ > 0: the light leans away from the hit.

    ``a`` and ``kappa`` have shape (bands, 3); ``views`` says how many vertices each band was estimated
    from.

    Examples
    --------
    >>> zero = np.zeros((len(BAND_EDGES_MM), 3))
    >>> round(float(FromViews(zero, zero).factor(np.array([0.3]), np.array([0.1]), np.array([2.0]))[0, 0]), 9)
    1.0
    """

    a: np.ndarray
    kappa: np.ndarray
    views: tuple = ()
    name: str = "from-views"
    needs_direction = True

    def factor(self, mu, s, r):
        band = _band(r)
        a = np.asarray(self.a, dtype=np.float64)[band]
        k = np.asarray(self.kappa, dtype=np.float64)[band]
        mu, s = (np.asarray(x, dtype=np.float64)[..., None] for x in (mu, s))
        return np.pi * (1 + a * mu) * np.exp(k * s) / _normalisation(a, k)

    def describe(self) -> dict:
        return {
            "law": self.name,
            "band_edges_mm": list(BAND_EDGES_MM),
            "a": np.round(np.asarray(self.a), 4).tolist(),
            "kappa": np.round(np.asarray(self.kappa), 4).tolist(),
            "views": list(self.views),
        }


def _band(r, edges=BAND_EDGES_MM) -> np.ndarray:
    """The band of ``edges`` (mm, the last one open) each distance ``r`` falls in."""
    i = np.searchsorted(edges, np.asarray(r, dtype=np.float64), side="right") - 1
    return np.clip(i, 0, len(edges) - 1)


#: the grid of (a, κ) :func:`fit_from_views` searches
A_GRID = np.linspace(-0.8, 3.0, 20)
KAPPA_GRID = np.linspace(-1.0, 4.0, 41)


def fit_from_views(L, var, mu, s, r, *, min_snr: float = 5.0) -> FromViews:
    r"""(a, κ) per distance band and channel from vertices seen by several cameras.

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
    vertices' exitances, :math:`\pi L_{vc} = M_v \gamma(\mu_{vc}, s_{vc})`: for each (a, κ) of the grid
    (:data:`A_GRID` × :data:`KAPPA_GRID`) the weighted least-squares :math:`M_v` are closed-form, and the
    (a, κ) of least :math:`\chi^2` is taken — a search, not a descent, since two or three views per
    vertex leave the problem flat in places.  Weights :math:`1/(\mathrm{Var}\,L + (0.02 L)^2)`.  A band
    with fewer than :data:`MIN_PAIRS` such vertices takes its nearest estimated band's values.
    """
    L, var, mu, s = (np.asarray(x, dtype=np.float64) for x in (L, var, mu, s))
    bands = len(BAND_EDGES_MM)
    band = _band(r)
    a_out = np.zeros((bands, 3))
    k_out = np.zeros((bands, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        good = np.isfinite(L) & (L / np.sqrt(var) >= min_snr)
    views = good.all(axis=2)  # (C, N)
    multi = views.sum(axis=0) >= 2
    counts = np.bincount(band[multi], minlength=bands)
    A, Kg = np.meshgrid(A_GRID, KAPPA_GRID, indexing="ij")
    norm = _normalisation(A, Kg)  # (na, nk)
    for b in range(bands):
        m = multi & (band == b)
        if m.sum() < MIN_PAIRS:
            continue
        v = views[:, m]
        mv, sv = mu[:, m][v], s[:, m][v]  # (n_views,)
        col = np.broadcast_to(np.arange(m.sum()), v.shape)[v]  # the vertex of each view
        # γ of every view under every (a, κ): (na, nk, n_views)
        g = np.pi * (1 + A[..., None] * mv) * np.exp(Kg[..., None] * sv) / norm[..., None]
        for ch in range(3):
            y = np.pi * L[:, m, ch][v]
            w = 1.0 / (np.pi**2 * (var[:, m, ch][v] + (0.02 * L[:, m, ch][v]) ** 2) + 1e-300)
            n = m.sum()
            num = np.zeros(g.shape[:2] + (n,))
            den = np.zeros_like(num)
            np.add.at(num, (slice(None), slice(None), col), w * g * y)  # Σ_c w γ y per vertex
            np.add.at(den, (slice(None), slice(None), col), w * g * g)
            M = num / np.maximum(den, 1e-300)
            chi2 = (w * (y - M[..., col] * g) ** 2).sum(axis=-1)
            i, j = np.unravel_index(np.argmin(chi2), chi2.shape)
            a_out[b, ch], k_out[b, ch] = A_GRID[i], KAPPA_GRID[j]
    ok = counts >= MIN_PAIRS
    if not ok.any():
        raise TranslucencyError(
            f"exit law: fewer than {MIN_PAIRS} vertices are seen well by two cameras in any band of "
            "distance; choose exit_law='lambertian' or exit_law='dielectric', or add views"
        )
    idx = np.arange(bands)
    nearest = np.array([idx[ok][np.argmin(np.abs(idx[ok] - i))] for i in idx])
    return FromViews(a_out[nearest], k_out[nearest], tuple(int(c) for c in counts))


#: distance bands (mm from the hit) of :class:`Tabulated`, the last one open
TABLE_EDGES_MM = (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0)


@dataclass(frozen=True)
class Tabulated(ExitLaw):
    r"""γ per distance band (:data:`TABLE_EDGES_MM`), exit bin and channel, ``gamma`` of shape (bands,
    bins.count, 3), from a photon tally's exit bins (:func:`tabulated_from_tally`).  For every band
    :math:`\sum_b \gamma_b \Omega'_b = \pi` (the bins tile the hemisphere), so the law keeps energy.

    Examples
    --------
    >>> from translucency.angles import ExitBins
    >>> law = Tabulated(ExitBins(2), np.ones((len(TABLE_EDGES_MM), 4, 3)), "flat")
    >>> law.factor(np.array([0.9, 0.2]), np.array([0.1, -0.3]), np.array([0.2, 7.0]))[:, 0].tolist()
    [1.0, 1.0]
    """

    bins: object  # translucency.angles.ExitBins
    gamma: np.ndarray
    source: str
    name: str = "tally"
    needs_direction = True

    def factor(self, mu, s, r):
        mu, s = np.asarray(mu, dtype=np.float64), np.asarray(s, dtype=np.float64)
        band = _band(r, TABLE_EDGES_MM)
        # the azimuth from the away axis: s = ω · t̂ over the length of ω's tangent part, √(1 − μ²)
        sin_theta = np.sqrt(np.clip(1.0 - mu**2, 0.0, 1.0))
        cos_phi = np.divide(s, sin_theta, out=np.ones_like(s), where=sin_theta > 1e-9)
        return np.asarray(self.gamma)[band, self.bins.bin_of(mu, cos_phi)]

    def describe(self) -> dict:
        return {
            "law": self.name,
            "source": self.source,
            "band_edges_mm": list(TABLE_EDGES_MM),
            "exit_bins": self.bins.describe(),
            "gamma": np.round(np.asarray(self.gamma), 4).tolist(),
        }


def tabulated_from_tally(path) -> Tabulated:
    r"""The exit law of a mesh data set with exit bins (its normal beams): per distance band from each
    incident point, the bins' R_d weighted by the vertices' areas, :math:`\gamma_b = \pi \sum_v A_v
    R_{d,b}(v) / (\Omega'_b \sum_v A_v R_d(v))`; a band without exits takes its nearest band's."""
    from ...io.mesh_dataset import open_mesh_dataset  # Zarr loads where a tally is read

    ds = open_mesh_dataset(path)
    bins = ds.exit_bins
    if bins is None:
        raise TranslucencyError(f"exit_law: {path} has no exit bins (see `acquire mesh --exit-bins`)")
    vertices = np.asarray(ds["vertices"], dtype=np.float64)
    area = np.asarray(ds["vertex_area"], dtype=np.float64)
    incident = np.asarray(ds["incident"])
    bands = len(TABLE_EDGES_MM)
    total = np.zeros((bands, bins.count, 3))
    for p, i in enumerate(incident):
        binned = np.asarray(ds.group["exit_bins"][p, 0], dtype=np.float64)  # (V, 3, B)
        band = _band(np.linalg.norm(vertices - vertices[i], axis=1), TABLE_EDGES_MM)
        np.add.at(total, band, np.einsum("vcb,v->vbc", binned, area))
    has = total.sum(axis=1).min(axis=1) > 0
    if not has.any():
        raise TranslucencyError(f"exit_law: {path} holds no exits")
    idx = np.arange(bands)
    nearest = np.array([idx[has][np.argmin(np.abs(idx[has] - b))] for b in idx])
    total = total[nearest]
    gamma = np.pi * total / (bins.projected_solid_angle * total.sum(axis=1, keepdims=True))
    return Tabulated(bins, gamma, str(path))


def law_named(name: str, eta: float = 1.0) -> ExitLaw | None:
    """The law a rig file names: ``"lambertian"``, ``"dielectric"`` (needs η ≠ 1), ``"tally:PATH"`` (a mesh
    data set with exit bins), ``"walk"`` (per cell and camera, from walks at each shot's fitted material)
    or ``"from-views"`` (None: it is estimated from the photographs)."""
    if name.startswith("tally:"):
        return tabulated_from_tally(name.split(":", 1)[1])
    if name == "lambertian":
        return Lambertian()
    if name == "dielectric":
        if eta == 1.0:
            raise TranslucencyError("exit_law: 'dielectric' needs the boundary's eta > 1")
        return Dielectric(float(eta))
    if name == "from-views":
        return None
    if name == "walk":
        return Walked()
    raise TranslucencyError(
        f"exit_law: one of lambertian, dielectric, from-views, walk, tally:PATH; got {name!r}"
    )


__all__ = [
    "ExitLaw",
    "Lambertian",
    "Dielectric",
    "FromViews",
    "Tabulated",
    "Walked",
    "fit_from_views",
    "tabulated_from_tally",
    "law_named",
    "BAND_EDGES_MM",
]
