r"""The profile of a homogeneous, index-matched, isotropically scattering half-space under a normal pencil
beam, from the photon walks' table (:mod:`translucency.acquire.half_space`).

In mean free paths the profile depends on the albedo alone:

.. math:: R_d(r; \sigma_t, \alpha) = \sigma_t^2\, f(\sigma_t r; \alpha)   \qquad [\text{mm}^{-2}]

with f tallied on a grid of albedos α = σ_s/σ_t and radial annuli ρ = σ_t r.  f is interpolated
linearly in log f between the annuli's centres (log ρ) and between albedos (log(1 − α)); past the last
well-counted annulus it falls exponentially with the slope of the last counted ones.  Unlike Jensen's
dipole it holds the near peak — the first scattering's 1/ρ core and the low orders — and its integral
is the half-space's total diffuse reflectance (energy is conserved by construction: R_tot < 1).

For a medium with g ≠ 0 it stands for the similar medium (σ_s' = σ_s (1 − g)): right far from the
beam, approximate within a transport mean free path of it.
"""

from __future__ import annotations

from functools import cache
from importlib import resources

import numpy as np

#: an annulus counts once it holds this many photons (fewer: its value is the extrapolated tail's)
MIN_COUNT = 30


@cache
def _table():
    """(log ρ centres, log(1 − α) grid, log f (A, B), R_total (A,)) of the shipped table, its tails
    extrapolated."""
    with resources.files("translucency.data").joinpath("half_space_profiles.npz").open("rb") as fh:
        t = dict(np.load(fh))
    edges, f, photons = t["rho_edges"], t["f"], float(t["photons"])
    centre = np.sqrt(edges[:-1] * edges[1:])
    centre[0] = 0.5 * edges[1]  # the first disc
    counts = f * photons * np.pi * np.diff(edges**2)
    logf = np.empty_like(f)
    for a in range(len(f)):
        ok = np.flatnonzero(counts[a] >= MIN_COUNT)
        last = ok.max()
        logf[a, : last + 1] = np.log(np.maximum(f[a, : last + 1], 1e-300))
        tail = ok[ok > last - 8][-6:]  # the slope of the last counted annuli, per ρ (exponential fall)
        slope = min(np.polyfit(centre[tail], np.log(f[a, tail]), 1)[0], -1e-3)
        logf[a, last + 1 :] = logf[a, last] + slope * (centre[last + 1 :] - centre[last])
    return np.log(centre), np.log1p(-t["albedo"]), logf, t["R_total"]


def half_space_table():
    """The shipped table as :func:`half_space_R_d` reads it: (log ρ at the annuli's centres (B,), log(1 − α)
    of its albedos (A,), log f (A, B) with the tails extrapolated, the total diffuse reflectance (A,)) —
    for a search over the albedos (:mod:`translucency.medium.estimate`)."""
    return _table()


def albedo_range() -> tuple[float, float]:
    """The albedos the table spans (outside, the nearest table albedo is used)."""
    _, u, _, _ = _table()
    return float(-np.expm1(u[0])), float(-np.expm1(u[-1]))


def half_space_R_d(r, sigma_t: float, albedo: float) -> np.ndarray:
    r"""R_d(r) in mm⁻² per unit incident power of the half-space (module notes).

    Parameters
    ----------
    r : array_like
        Distances from the beam's entry, mm.
    sigma_t : float
        Extinction σ_a + σ_s (or σ_a + σ_s'), mm⁻¹.
    albedo : float
        σ_s / σ_t, within :func:`albedo_range` (clipped to it).

    Examples
    --------
    Its integral is the half-space's total diffuse reflectance (the table's tally, within 1 %),
    whatever σ_t:

    >>> r = np.concatenate([np.linspace(0, 0.01, 2001)[1:], np.geomspace(0.01, 400.0, 100_000)])
    >>> def total(sigma_t):  # the same grid in mean free paths
    ...     d = r / sigma_t
    ...     return float(np.trapezoid(2 * np.pi * d * half_space_R_d(d, sigma_t, 0.95), d))
    >>> round(total(1.0) / half_space_total(0.95), 2), round(total(3.0) / half_space_total(0.95), 2)
    (1.0, 1.0)
    """
    logc, u, logf, _ = _table()
    uu = np.clip(np.log1p(-albedo), u[-1], u[0])  # u decreases with α
    k = int(np.clip(np.searchsorted(-u, -uu) - 1, 0, len(u) - 2))
    w = (uu - u[k]) / (u[k + 1] - u[k])
    row = (1 - w) * logf[k] + w * logf[k + 1]
    rho = np.maximum(np.asarray(r, dtype=np.float64) * sigma_t, np.exp(logc[0]))
    lr = np.log(rho)
    inside = lr <= logc[-1]
    out = np.interp(lr, logc, row)
    # past the table: the exponential tail of its last two centres
    slope = (row[-1] - row[-2]) / (np.exp(logc[-1]) - np.exp(logc[-2]))
    out = np.where(inside, out, row[-1] + slope * (rho - np.exp(logc[-1])))
    return sigma_t**2 * np.exp(out)


def half_space_total(albedo: float) -> float:
    """The half-space's total diffuse reflectance at ``albedo`` (the table's own tally, interpolated)."""
    _, u, _, total = _table()
    return float(np.interp(-np.log1p(-albedo), -u, total))


__all__ = ["half_space_R_d", "half_space_total", "half_space_table", "albedo_range"]
