r"""Photon beam diffusion (PBD) of Habel, Christensen and Jarosz (2013).

The profile pbrt-v4 tabulates (``BeamDiffusionMS`` + ``BeamDiffusionSS`` in its
``bssrdf.cpp``), here for normal incidence on a semi-infinite medium with
absorption :math:`\sigma_a`, reduced scattering :math:`\sigma_s'` (mm⁻¹) and
relative index :math:`\eta`:

.. math::

   R_d(r) = \rho'^2 \int_0^\infty \sigma_t' e^{-\sigma_t' t}\,\kappa(t)\,
            \bigl[C_\phi\,\phi(r, t) + C_E\,E_n(r, t)\bigr]\,dt
          + \int_{t_c}^\infty \sigma_s' e^{-\sigma_t' (t + d)}\,
            \frac{T(\mu)\,\mu}{4\pi d^2}\,dt ,

the *multiple-scattering* beam: a PBD point source at every depth t of the
refracted beam (weight :math:`\sigma_t' e^{-\sigma_t' t}`, albedo
:math:`\rho' = \sigma_s'/\sigma_t'` twice as in pbrt), with

* the Grosjean diffusion coefficient :math:`D_G = (2\sigma_a + \sigma_s')/(3\sigma_t'^2)`,
  :math:`\sigma_{tr} = \sqrt{\sigma_a / D_G}`;
* the extrapolated boundary :math:`z_b = 2 D_G (1 + 3C_2)/(1 - 2C_1)` above the
  surface, the image source at depth :math:`-(t + 2z_b)`, distances
  :math:`d_r = \sqrt{r^2 + t^2}`, :math:`d_v = \sqrt{r^2 + (t + 2z_b)^2}`;
* fluence :math:`\phi = \frac{1}{4\pi D_G}\bigl(e^{-\sigma_{tr} d_r}/d_r - e^{-\sigma_{tr} d_v}/d_v\bigr)`
  and the normal flux :math:`E_n = \frac{1}{4\pi}\bigl(t(1+\sigma_{tr}d_r)e^{-\sigma_{tr}d_r}/d_r^3
  + (t + 2z_b)(1+\sigma_{tr}d_v)e^{-\sigma_{tr}d_v}/d_v^3\bigr)`;
* the exitance weights of the PBD boundary condition :math:`C_\phi = (1 - 2C_1)/4`,
  :math:`C_E = (1 - 3C_2)/2` from the Fresnel moments
  :math:`C_n = \int_0^1 F_r(\mu)\,\mu^n d\mu` of internal reflection;
* Habel's correction :math:`\kappa = 1 - e^{-2\sigma_t'(d_r + t)}` (the source
  near the surface has not yet diffused);

and the *single-scattering* term (pbrt's ``BeamDiffusionSS``), which sees the
*real* coefficients and the phase function: with the medium's mean cosine g,
:math:`\sigma_s = \sigma_s'/(1 - g)`, :math:`\sigma_t = \sigma_a + \sigma_s`,

.. math::

   R_d^{SS}(r) = \int_{t_c}^\infty \sigma_s e^{-\sigma_t (t + d)}\,
                 p_{HG}(\mu; g)\,\frac{T(\mu)\,\mu}{d^2}\,dt, \qquad
   p_{HG}(\mu; g) = \frac{1}{4\pi}\frac{1 - g^2}{(1 + g^2 + 2 g \mu)^{3/2}},

:math:`d = \sqrt{r^2 + t^2}`, :math:`\mu = t/d` (the light turns by π − arccos μ from the beam
going down to the path going up, so g > 0 makes this single bounce back *rarer*), the Fresnel
transmittance :math:`T = 1 - F_r(\mu)` and :math:`t_c = r\sqrt{\eta^2 - 1}` (shallower paths
are totally reflected).  At g = 0 this is the isotropic term in the reduced coefficients.
Both beam integrals run over the CDF of the exponential, :math:`u = 1 - e^{-\sigma_t' t}`,
by Gauss–Legendre in
:math:`w = u^{1/3}` (nodes crowd the surface, where the integrand peaks at
small r); pbrt uses 100 midpoints in u.

Without κ the multiple-scattering total is closed form (each point source's
fluence and flux integrate over the plane to :math:`e^{-\sigma_{tr} z}` terms):

.. math::

   \int 2\pi r R_d^{MS}\,dr = \rho'^2 \frac{\sigma_t'}{\sigma_t' + \sigma_{tr}}
     \Bigl[\frac{C_\phi}{2 D_G \sigma_{tr}}\bigl(1 - e^{-2\sigma_{tr} z_b}\bigr)
     + \frac{C_E}{2}\bigl(1 + e^{-2\sigma_{tr} z_b}\bigr)\Bigr],

which is exactly 1 for a conservative medium (σ_a = 0: every photon that
enters leaves): :func:`pbd_total_without_kappa`, checked in the tests.
"""

from __future__ import annotations

from abc import abstractmethod
from functools import lru_cache

import numpy as np

from .._validate import TranslucencyError
from ._base import MediumStorage, ReflectanceModel, medium_parameters
from .alpha import Modulation

#: Gauss–Legendre nodes of the beam integrals (over w = u^{1/3}, u the exponential's CDF)
BEAM_NODES = 32
#: the radial energy table: geometric panels from R_TABLE[0] to R_TABLE[1] mm, 8 nodes each
R_TABLE = (1e-4, 1e4)
_PANELS, _PANEL_NODES = 128, 8


def fresnel_dielectric(cos_i, n_rel) -> np.ndarray:
    """Unpolarised Fresnel reflectance for light arriving at cosine ``cos_i`` on a boundary
    into a medium of relative index ``n_rel`` = n_t / n_i (1 beyond the critical angle)."""
    cos_i = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)
    n_rel = np.asarray(n_rel, dtype=np.float64)
    sin_t2 = (1.0 - cos_i**2) / n_rel**2
    cos_t = np.sqrt(np.maximum(1.0 - sin_t2, 0.0))
    rs = (cos_i - n_rel * cos_t) / (cos_i + n_rel * cos_t)
    rp = (n_rel * cos_i - cos_t) / (n_rel * cos_i + cos_t)
    return np.where(sin_t2 >= 1.0, 1.0, 0.5 * (rs**2 + rp**2))


_GL200 = np.polynomial.legendre.leggauss(200)


@lru_cache(maxsize=256)
def fresnel_moment(n: int, eta: float, side: str = "inside") -> float:
    """:math:`C_n = \\int_0^1 F_r(\\mu)\\,\\mu^n d\\mu`, the n-th Fresnel moment, by quadrature.

    ``side="inside"``: light inside a medium of relative index η meeting its
    boundary (total reflection beyond the critical angle; the moments of the
    diffusion boundary conditions).  ``"outside"``: light from the outside.

    Examples
    --------
    >>> round(float(2 * fresnel_moment(1, 1.3)), 3)   # ≈ Jensen's F_dr(1.3) = 0.4448
    0.444
    """
    eta = float(eta)
    if not eta > 0:
        raise TranslucencyError(f"eta: must be > 0, got {eta}")
    n_rel = 1.0 / eta if side == "inside" else eta
    # split at the critical cosine (the kink of TIR), Gauss–Legendre on each side
    mu_c = np.sqrt(max(0.0, 1.0 - n_rel**2)) if n_rel < 1.0 else 0.0
    x, w = _GL200
    total = 0.0
    for a, b in ((0.0, mu_c), (mu_c, 1.0)):
        if b > a:
            mu = a + (b - a) * (x + 1.0) / 2.0
            total += (b - a) / 2.0 * float(np.sum(w * fresnel_dielectric(mu, n_rel) * mu**n))
    return total


def _beam_nodes():
    """Nodes u in (0, 1) of the exponential's CDF and their weights (Σ = 1): u = w³, w Gauss–Legendre."""
    x, wt = np.polynomial.legendre.leggauss(BEAM_NODES)
    w = (x + 1.0) / 2.0
    return w**3, 3.0 * w**2 * wt / 2.0


_U, _WU = _beam_nodes()
_TAU = -np.log1p(-_U)  # optical depth σ_t' t of each node


def pbd_coefficients(sigma_a, sigma_s_prime, eta) -> dict:
    """σ_t', ρ', D_G, σ_tr (mm⁻¹ / mm), z_b (mm), C_φ and C_E of the PBD (module docstring).

    Examples
    --------
    >>> k = pbd_coefficients(0.0, 1.0, 1.0)   # index-matched: C_φ = 1/4, C_E = 1/2
    >>> round(float(k["C_phi"]), 6), round(float(k["C_E"]), 6), round(float(k["z_b"]), 6)
    (0.25, 0.5, 0.666667)
    """
    sigma_a = np.asarray(sigma_a, dtype=np.float64)
    sigma_s_prime = np.asarray(sigma_s_prime, dtype=np.float64)
    sigma_t = sigma_a + sigma_s_prime
    C1, C2 = fresnel_moment(1, float(eta)), fresnel_moment(2, float(eta))
    D_G = (2.0 * sigma_a + sigma_s_prime) / (3.0 * sigma_t**2)
    return {
        "sigma_t_prime": sigma_t,
        "rho_prime": sigma_s_prime / sigma_t,
        "D_G": D_G,
        "sigma_tr": np.sqrt(sigma_a / D_G),
        "z_b": 2.0 * D_G * (1.0 + 3.0 * C2) / (1.0 - 2.0 * C1),
        "C_phi": 0.25 * (1.0 - 2.0 * C1),
        "C_E": 0.5 * (1.0 - 3.0 * C2),
    }


def _beam_kernel(r, sigma_a, sigma_s, C1, C2, eta, g, U, WU, kappa, multiple, single):  # pragma: no cover
    """Σ over the beam nodes (optical depths U) of the MS and/or SS integrands, per element (compiled by
    Numba: :func:`_compiled_kernel`); ``sigma_s`` is σ_s', g the phase function's mean cosine."""
    out = np.zeros(r.size)
    t_crit = np.sqrt(max(eta * eta - 1.0, 0.0))
    n_in = 1.0 / eta  # relative index seen from inside
    for e in range(r.size):
        ri, sa, ss = r[e], sigma_a[e], sigma_s[e]
        st = sa + ss
        rho = ss / st
        D = (2.0 * sa + ss) / (3.0 * st * st)
        sig = np.sqrt(sa / D)
        zb = 2.0 * D * (1.0 + 3.0 * C2) / (1.0 - 2.0 * C1)
        c_phi, c_E = 0.25 * (1.0 - 2.0 * C1), 0.5 * (1.0 - 3.0 * C2)
        acc = 0.0
        if multiple:
            ms = 0.0
            for q in range(U.size):
                # source depth t (mm), real and image distances (mm)
                t = U[q] / st
                d_r = np.sqrt(ri * ri + t * t)
                h_v = t + 2.0 * zb
                d_v = np.sqrt(ri * ri + h_v * h_v)
                e_r, e_v = np.exp(-sig * d_r), np.exp(-sig * d_v)
                phi = (e_r / d_r - e_v / d_v) / (4.0 * np.pi * D)
                E_n = (
                    t * (1.0 + sig * d_r) * e_r / (d_r * d_r * d_r)
                    + h_v * (1.0 + sig * d_v) * e_v / (d_v * d_v * d_v)
                ) / (4.0 * np.pi)
                f = c_phi * phi + c_E * E_n
                if kappa:
                    f *= -np.expm1(-2.0 * st * (d_r + t))
                ms += WU[q] * f
            acc += rho * rho * ms
        if single:
            # the real coefficients (mm⁻¹): σ_s = σ_s'/(1 − g), σ_t = σ_a + σ_s
            ss_real = ss / (1.0 - g)
            st_real = sa + ss_real
            rr = max(ri, 1e-12)
            t_c = rr * t_crit
            s_acc = 0.0
            for q in range(U.size):
                # scattering depth t = t_c + s (mm), path d to x_o (mm), its cosine μ, Fresnel transmittance
                t = t_c + U[q] / st_real
                d = np.sqrt(rr * rr + t * t)
                mu = t / d
                sin_t2 = (1.0 - mu * mu) / (n_in * n_in)
                if sin_t2 >= 1.0:
                    continue
                cos_t = np.sqrt(1.0 - sin_t2)
                rs = (mu - n_in * cos_t) / (mu + n_in * cos_t)
                rp = (n_in * mu - cos_t) / (n_in * mu + cos_t)
                T = 1.0 - 0.5 * (rs * rs + rp * rp)
                denom = 1.0 + g * g + 2.0 * g * mu
                p_hg = (1.0 - g * g) / (4.0 * np.pi * denom * np.sqrt(denom))
                s_acc += WU[q] * np.exp(-st_real * (t_c + d)) * p_hg * T * mu / (d * d)
            acc += ss_real / st_real * s_acc
        out[e] = acc
    return out


@lru_cache(maxsize=1)
def _compiled_kernel():
    """:func:`_beam_kernel` compiled by Numba, on first use (a model file is read without Numba)."""
    from numba import njit  # heavy: Numba loads only where a PBD or directional-dipole profile is evaluated

    return njit(cache=True, nogil=True)(_beam_kernel)


def mean_cosine(g) -> float:
    """The phase function's mean cosine g as a float, checked to lie in (−1, 1)."""
    g = float(g)
    if not -1.0 < g < 1.0:
        raise TranslucencyError(f"g: the phase function's mean cosine must be in (-1, 1), got {g}")
    return g


def _beam(r, sigma_a, sigma_s_prime, eta, *, g=0.0, kappa=True, multiple=True, single=True) -> np.ndarray:
    """Broadcast r (mm), σ_a, σ_s' (mm⁻¹) and run :func:`_beam_kernel` over the elements."""
    g = mean_cosine(g)
    r, sa, ss = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (r, sigma_a, sigma_s_prime)))
    shape = r.shape
    C1, C2 = fresnel_moment(1, float(eta)), fresnel_moment(2, float(eta))
    flat = (np.ascontiguousarray(v).ravel() for v in (r, sa, ss))
    out = _compiled_kernel()(*flat, C1, C2, float(eta), g, _TAU, _WU, kappa, multiple, single)
    return out.reshape(shape)


def pbd_multiple(r, sigma_a, sigma_s_prime, eta, *, kappa: bool = True) -> np.ndarray:
    """The multiple-scattering beam :math:`R_d^{MS}(r)` in mm⁻² (``kappa=False``: without Habel's κ)."""
    return _beam(r, sigma_a, sigma_s_prime, eta, kappa=kappa, single=False)


def pbd_single(r, sigma_a, sigma_s_prime, eta, *, g: float = 0.0) -> np.ndarray:
    """The single-scattering term :math:`R_d^{SS}(r)` in mm⁻² (Henyey–Greenstein phase function of
    mean cosine g, the real σ_s = σ_s'/(1 − g))."""
    return _beam(r, sigma_a, sigma_s_prime, eta, g=g, multiple=False)


def pbd_R_d(r, sigma_a, sigma_s_prime, eta, *, g: float = 0.0, single: bool = True) -> np.ndarray:
    """Photon beam diffusion :math:`R_d(r)` in mm⁻² at distance r (mm): multiple + single scattering.

    Parameters broadcast against each other; g (the medium's mean cosine) enters the single
    scattering only (the diffusion sees σ_s' alone).

    Examples
    --------
    >>> round(float(pbd_R_d(1.0, 0.0021, 2.19, 1.3)), 4)   # marble, red, r = 1 mm
    0.0414
    """
    return _beam(r, sigma_a, sigma_s_prime, eta, g=g, single=single)


def pbd_total_without_kappa(sigma_a, sigma_s_prime, eta) -> np.ndarray:
    """Closed-form :math:`\\int 2\\pi r R_d^{MS} dr` of the beam without κ (module docstring).

    Examples
    --------
    >>> round(float(pbd_total_without_kappa(0.0, 1.0, 1.3)), 12)   # conservative: all light leaves
    1.0
    """
    k = pbd_coefficients(sigma_a, sigma_s_prime, eta)
    sig, zb, st = k["sigma_tr"], k["z_b"], k["sigma_t_prime"]
    e = np.exp(-2.0 * sig * zb)
    # (1 − e^{−2σ z_b}) / σ → 2 z_b as σ → 0
    ratio = np.where(sig > 0, -np.expm1(-2.0 * sig * zb) / np.where(sig > 0, sig, 1.0), 2.0 * zb)
    inner = k["C_phi"] * ratio / (2.0 * k["D_G"]) + 0.5 * k["C_E"] * (1.0 + e)
    return k["rho_prime"] ** 2 * st / (st + sig) * inner


def radial_table(profile, shape) -> tuple[np.ndarray, np.ndarray]:
    """Enclosed energy :math:`\\int_0^R 2\\pi r f(r) dr` of radial profiles on a fixed grid of R.

    ``profile(r)`` maps radii (G,) to values ``shape + (G,)`` (mm⁻²).  Composite
    Gauss–Legendre on geometric panels between :data:`R_TABLE` (the disk inside
    the first radius counts as f(r₀) π r₀²).  Returns the panel edges (E,) in mm
    and the energy at each edge, ``shape + (E,)`` (the last: the total).
    """
    edges = np.geomspace(*R_TABLE, _PANELS + 1)
    x, w = np.polynomial.legendre.leggauss(_PANEL_NODES)
    half = np.diff(edges)[:, None] / 2.0
    r = (edges[:-1, None] + half * (x + 1.0)).ravel()
    f = np.asarray(profile(r)).reshape(tuple(shape) + (_PANELS, _PANEL_NODES))
    panel = np.einsum("...pq,pq->...p", f, 2.0 * np.pi * r.reshape(_PANELS, _PANEL_NODES) * half * w)
    first = np.asarray(profile(np.array([edges[0]]))).reshape(tuple(shape) + (1,)) * np.pi * edges[0] ** 2
    return edges, np.concatenate([first, first + np.cumsum(panel, axis=-1)], axis=-1)


def table_energy_within(edges, energy, radius) -> np.ndarray:
    """Energy inside ``radius`` (broadcast against ``energy[..., 0]``) from :func:`radial_table`,
    linear in log r between edges; 0 at r = 0, the total beyond the last edge."""
    radius = np.asarray(radius, dtype=np.float64)
    lr = np.log(np.clip(radius, edges[0], edges[-1]))
    le = np.log(edges)
    j = np.clip(np.searchsorted(le, lr) - 1, 0, len(edges) - 2)
    t = (lr - le[j]) / (le[j + 1] - le[j])
    e0 = np.take_along_axis(energy, j[..., None], axis=-1)[..., 0]
    e1 = np.take_along_axis(energy, (j + 1)[..., None], axis=-1)[..., 0]
    out = e0 + t * (e1 - e0)
    small = radius < edges[0]
    return np.where(small, energy[..., 0] * (radius / edges[0]) ** 2, out)


class _TabulatedRadialModel(MediumStorage, ReflectanceModel):
    """A per-point radial profile with parameters (σ_a, σ_s') per channel and a global η,
    whose enclosed energy comes from a table (:func:`radial_table`), built on first use."""

    def __init__(self, x_i, sigma_a, sigma_s_prime, eta: float, alpha: Modulation, *, frame=None):
        super().__init__(x_i, alpha, frame)
        self.sigma_a, self.sigma_s_prime, self.eta = medium_parameters(
            self.n_points, sigma_a, sigma_s_prime, eta
        )
        self._table = None

    @abstractmethod
    def _R(self, r, sigma_a, sigma_s_prime):
        """The family's R_d(r) in mm⁻² per parameter set (PBD, the directional dipole)."""

    def profile(self, i, r, theta) -> np.ndarray:
        """:math:`R_d(r)` per channel (rotationally symmetric: θ is unused)."""
        i = np.asarray(i)
        return self._R(np.asarray(r)[..., None], self.sigma_a[i], self.sigma_s_prime[i])

    def energy_within(self, i, radius) -> np.ndarray:
        if self._table is None:  # every point's enclosed energy on the fixed grid, in blocks of points
            tables = []
            for s in range(0, self.n_points, 64):
                sa, ss = self.sigma_a[s : s + 64, :, None], self.sigma_s_prime[s : s + 64, :, None]
                edges, e = radial_table(lambda r, sa=sa, ss=ss: self._R(r, sa, ss), sa.shape[:2])
                tables.append(e)
            self._table = (edges, np.concatenate(tables))
        edges, energy = self._table
        i = np.asarray(i)
        radius = np.broadcast_to(np.asarray(radius, dtype=np.float64), i.shape)
        return table_energy_within(edges, energy[i], radius[..., None])


class PBDModel(_TabulatedRadialModel):
    """Photon beam diffusion per incident point (σ_a, σ_s' per channel, mm⁻¹), with α.

    Parameters
    ----------
    x_i : array_like, shape (N, 2) or (N, 3)
        Incident points in mm.
    sigma_a, sigma_s_prime : array_like, shape (N, 3)
        Absorption and reduced scattering per point and channel, mm⁻¹.
    eta : float
        Relative index of refraction of the boundary.
    alpha : PlanarAlpha or VertexAlpha
        Modulation texture.
    g : float, optional
        The medium's mean cosine of scattering, in (−1, 1), shared by all points: the single-scattering
        term's phase function and real σ_s = σ_s'/(1 − g) (0: isotropic, as files without g are read).

    Examples
    --------
    >>> from translucency.model import PlanarAlpha
    >>> m = PBDModel([[0.0, 0.0]], [[0.0, 0.0, 0.0]], [[1.0, 1.0, 1.0]], 1.3,
    ...              PlanarAlpha(np.ones((2, 2)), (-1.0, -1.0), 1.0))
    >>> 0.95 < float(m.total_reflectance()[0, 0]) < 1.05   # conservative: ≈ all light leaves
    True
    """

    kind = "pbd"

    def __init__(self, x_i, sigma_a, sigma_s_prime, eta: float, alpha: Modulation, *, frame=None, g=0.0):
        super().__init__(x_i, sigma_a, sigma_s_prime, eta, alpha, frame=frame)
        self.g = mean_cosine(g)

    def header_fields(self) -> dict:
        return {"eta": self.eta, "g": self.g}

    @classmethod
    def from_stored(cls, x_i, params, alpha, frame, header):
        return cls(
            x_i,
            params["sigma_a"],
            params["sigma_s_prime"],
            header["eta"],
            alpha,
            frame=frame,
            g=header.get("g", 0.0),
        )

    def _R(self, r, sigma_a, sigma_s_prime):
        return pbd_R_d(r, sigma_a, sigma_s_prime, self.eta, g=self.g)
