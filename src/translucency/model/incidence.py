r"""How much of the light arriving at an angle a translucent body sends back: the incidence law.

Data acquired with normally incident beams (the virtual DISCO, ``acquire mesh``, a lab's laser) measure
each point's total diffuse reflectance at :math:`\mu_0 = \cos\theta_i = 1` only.  Light that arrives
obliquely enters shallower and more of it comes back out: under a sky, where most light is oblique, a
normal-incidence tally is too dark (skin: about 10 %), and a grazing point light on a curved flank too.

For a semi-infinite medium behind an index-matched boundary with isotropic scattering of albedo
:math:`a` (for g ≠ 0 the reduced albedo :math:`a' = \sigma_s' / (\sigma_s' + \sigma_a)` by similarity),
the total reflectance for incidence :math:`\mu_0` — Chandrasekhar's plane albedo — is exact:

.. math:: R(\mu_0) = 1 - H(\mu_0)\, \sqrt{1 - a},

with Chandrasekhar's H-function of isotropic scattering, the solution of

.. math:: \frac{1}{H(\mu)} = \sqrt{1 - a} + \frac{a}{2} \int_0^1 \frac{x\, H(x)}{\mu + x}\, dx

(Chandrasekhar 1960, *Radiative Transfer*, eq. V.(10)-(11); Bosma & de Rooij 1983 for this form).  A
point whose normal-incidence reflectance :math:`R_1` was measured gets the albedo with
:math:`R(1) = R_1`, and the light arriving at :math:`\mu_0` is weighted by

.. math:: F(\mu_0; R_1) = R(\mu_0) / R(1),

which is 1 at normal incidence, grows toward grazing, and keeps :math:`R(\mu_0) \le 1` (reflectance
bounded).  The renderer applies F per vertex and channel to the irradiance
(:func:`translucency.transport.irradiance.vertex_irradiance`); it holds for index-matched objects only — a
dielectric boundary's internal reflection changes the law, and there only the Fresnel transmittance's
ratio is applied.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from .._validate import TranslucencyError
from ..mitsuba import drjit, mitsuba

#: Gauss–Legendre nodes of the H-function's integral on [0, 1]
H_NODES = 32
#: the table's albedos: 1 − a from 1e-8 to 0.999, log-spaced
_EPS = np.logspace(-8.0, np.log10(0.999), 241)
#: the table's cosines of incidence, even in √μ (H rises steeply from μ = 0)
_MU = np.linspace(0.0, 1.0, 101) ** 2


def _nodes():
    x, w = np.polynomial.legendre.leggauss(H_NODES)
    return 0.5 * (x + 1.0), 0.5 * w


def chandrasekhar_h(mu, albedo) -> np.ndarray:
    r"""Chandrasekhar's H-function of isotropic scattering, :math:`H(\mu; a)`.

    Solves the integral equation of the module docstring at 32 Gauss–Legendre nodes by Newton's method
    (batched over albedos; quadratic convergence even near the conservative limit a → 1, where the plain
    iteration stalls) and evaluates it at ``mu`` by the equation itself (Nyström).

    Parameters
    ----------
    mu : array_like
        Cosines in [0, 1].
    albedo : array_like
        Single-scattering albedos in [0, 1]; broadcast against ``mu``.

    Returns
    -------
    ndarray
        H, ≥ 1; H(0) = 1.

    Examples
    --------
    >>> float(chandrasekhar_h(1.0, 1.0).round(3))  # the conservative case: 2.9078 (Chandrasekhar's table)
    2.908
    """
    mu, albedo = np.broadcast_arrays(np.asarray(mu, np.float64), np.asarray(albedo, np.float64))
    flat_a = albedo.ravel()
    unique, inverse = np.unique(flat_a, return_inverse=True)
    x, w = _nodes()
    h = _h_at_nodes(unique)  # (A, N)
    s = np.sqrt(np.maximum(1.0 - unique, 0.0))[inverse]
    integral = 0.5 * unique[inverse, None] * (w * x * h[inverse]) / (mu.ravel()[:, None] + x)
    return (1.0 / (s + integral.sum(axis=1))).reshape(mu.shape)


def _h_at_nodes(albedo: np.ndarray) -> np.ndarray:
    r"""H at the nodes for each albedo (A, N).

    Newton on :math:`G_i(h) = h_i (s + \tfrac{a}{2}\sum_j M_{ij} h_j) - 1`, :math:`s = \sqrt{1-a}`.
    """
    x, w = _nodes()
    M = w * x / (x[:, None] + x)  # M_ij = w_j x_j / (x_i + x_j)
    a = albedo[:, None]
    s = np.sqrt(np.maximum(1.0 - albedo, 0.0))[:, None]
    h = (1.0 + 2.0 * x) / (1.0 + 2.0 * x * s)  # Hapke's approximation as the start
    eye = np.eye(len(x))
    for _ in range(60):
        Mh = h @ M.T  # (A, N): Σ_j M_ij h_j
        G = h * (s + 0.5 * a * Mh) - 1.0
        if np.max(np.abs(G)) < 1e-13:
            break
        J = eye * (s + 0.5 * a * Mh)[:, :, None] + 0.5 * a[:, :, None] * h[:, :, None] * M
        h = h - np.linalg.solve(J, G[:, :, None])[:, :, 0]
    return h


def plane_albedo(mu, albedo) -> np.ndarray:
    r""":math:`R(\mu_0) = 1 - H(\mu_0; a) \sqrt{1-a}`: a half-space's total diffuse reflectance for light
    incident at :math:`\mu_0` (index-matched boundary, isotropic scattering).

    Examples
    --------
    >>> float(plane_albedo(1.0, 0.958).round(4))  # iadpython's adding-doubling gives 0.5635
    0.5636
    """
    albedo = np.asarray(albedo, np.float64)
    return 1.0 - chandrasekhar_h(mu, albedo) * np.sqrt(np.maximum(1.0 - albedo, 0.0))


@lru_cache(maxsize=1)
def _table():
    """R(1) on the albedo grid (increasing as 1 − a falls) and F(μ; a) = R(μ)/R(1) on the grid (A, M)."""
    a = 1.0 - _EPS
    R = plane_albedo(_MU[None, :], a[:, None])  # (A, M)
    return R[:, -1], R / R[:, -1:]


def incidence_factor(mu, reflectance) -> np.ndarray:
    r""":math:`F(\mu_0; R_1) = R(\mu_0)/R(1)` for a point whose normal-incidence total reflectance is R_1.

    The albedo comes from inverting :math:`R(1) = R_1` (monotone); both steps interpolate a table over
    1 − a (log-spaced, 10⁻⁸ … 0.999) and √μ (101 steps), accurate to 10⁻³.  R_1 is clipped to the
    table's range (0.0005 … 0.9998); μ ≤ 0 (light from behind the tangent plane) gives 0.

    Parameters
    ----------
    mu : array_like
        Cosines of incidence.
    reflectance : array_like
        R_1 (dimensionless, in [0, 1)), broadcast against ``mu``.

    Examples
    --------
    >>> f = incidence_factor([1.0, 0.5, 0.1], 0.5636)  # skin's blue: a = 0.958
    >>> [round(float(v), 2) for v in f]
    [1.0, 1.16, 1.34]
    """
    mu, R1 = np.broadcast_arrays(np.asarray(mu, np.float64), np.asarray(reflectance, np.float64))
    return _factor_at(albedo_coordinate(R1), mu)


def albedo_coordinate(reflectance) -> np.ndarray:
    """The table's albedo coordinate (fractional row) of each R_1: the costly half of
    :func:`incidence_factor`, computed once per vertex by :class:`HalfSpaceIncidence`."""
    R_normal, _ = _table()
    log_eps = np.log(_EPS)
    # albedo (as log(1 − a)) from R_1: R_normal falls as log(1 − a) grows
    R1 = np.asarray(reflectance, np.float64)
    q = np.interp(np.clip(R1, R_normal[-1], R_normal[0]), R_normal[::-1], log_eps[::-1])
    return np.clip((q - log_eps[0]) / (log_eps[1] - log_eps[0]), 0.0, len(_EPS) - 1.000001)


def _factor_at(fa: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """F at albedo coordinates ``fa`` and cosines ``mu`` (broadcast): bilinear in (log(1 − a), √μ)."""
    _, F = _table()
    fa, mu = np.broadcast_arrays(fa, np.asarray(mu, np.float64))
    # (a vertex without a normal — all its triangles degenerate — has no cosine: no light, F = 0)
    fm = np.sqrt(np.clip(np.nan_to_num(mu, nan=0.0), 0.0, 1.0)) * (len(_MU) - 1)
    fm = np.minimum(fm, len(_MU) - 1.000001)
    ia, im = fa.astype(int), fm.astype(int)
    ta, tm = fa - ia, fm - im
    out = (
        (1 - ta) * (1 - tm) * F[ia, im]
        + (1 - ta) * tm * F[ia, im + 1]
        + ta * (1 - tm) * F[ia + 1, im]
        + ta * tm * F[ia + 1, im + 1]
    )
    return np.where(mu > 0, out, 0.0)


def cosine_mean(reflectance) -> np.ndarray:
    r""":math:`\langle F \rangle = 2 \int_0^1 F(\mu; R_1)\, \mu\, d\mu`: how much more a point sends back
    under a uniform sky than its normal-incidence total says (32-point Gauss–Legendre)."""
    x, w = _nodes()
    R1 = np.asarray(reflectance, np.float64)
    return 2.0 * np.einsum("k,...k->...", w * x, incidence_factor(x, R1[..., None]))


@dataclass(frozen=True)
class NormalIncidence:
    """The data's own law: every direction counts as the normal incidence the data were measured with,
    and the exit is Lambertian."""

    name = "normal"

    def factor(self, cos_i: np.ndarray) -> np.ndarray | None:
        """None: no factor (the irradiance stays as it is)."""
        return None

    def exit(self, cos_o: np.ndarray) -> np.ndarray | None:
        """None: a Lambertian exit (π L = M)."""
        return None

    def at(self, vertices) -> NormalIncidence:
        """The same law for a few of the vertices."""
        return self

    def kernel(self):
        """None: no factor in a wavefront either (:meth:`HalfSpaceIncidence.kernel`)."""
        return None


@dataclass(frozen=True)
class HalfSpaceIncidence:
    r"""Chandrasekhar's plane albedo per vertex: light arriving at :math:`\mu_0` weighted by
    :math:`F(\mu_0; R_{1,v})` (module docstring), with R_1 the vertex's measured normal-incidence total;
    with ``both_ways`` the exit too, by reciprocity.

    **Exit.**  The diffuse transport is reciprocal, :math:`S(x_i, \omega_i; x_o, \omega_o) =
    S(x_o, \omega_o; x_i, \omega_i)`: a boundary that takes in :math:`F(\mu_i)` more of oblique light
    sends out :math:`F(\mu_o)` more toward oblique views.  Under a uniform sky of radiance L a half-space
    reflects exactly :math:`L\, R(\mu_o)` toward :math:`\mu_o`; the exit factor that gives this and keeps
    the exitance M is

    .. math:: \frac{\pi L(\mu_o)}{M} = \frac{F(\mu_o; R_1)}{\langle F \rangle}, \qquad
              \langle F \rangle = 2 \int_0^1 F(\mu)\, \mu\, d\mu

    (:func:`cosine_mean`): the limb brightens, a face-on view darkens by :math:`1/\langle F\rangle`.

    Parameters
    ----------
    reflectance : ndarray, shape (V, 3)
        Each vertex's normal-incidence total diffuse reflectance per channel.
    both_ways : bool
        Also the exit (default); False: the irradiance only (the ablation ``half-space-in``).
    """

    reflectance: np.ndarray
    both_ways: bool = True

    @property
    def name(self) -> str:
        return "half-space" if self.both_ways else "half-space-in"

    @cached_property
    def _albedo(self) -> np.ndarray:
        """(V, 3) the table's albedo coordinate of each vertex and channel (:func:`albedo_coordinate`)."""
        return albedo_coordinate(self.reflectance)

    def factor(self, cos_i: np.ndarray) -> np.ndarray:
        """F per vertex and channel for cosines ``cos_i`` of shape (V,) or (V, K): (V, 3) or (V, K, 3)."""
        cos_i = np.asarray(cos_i, np.float64)
        fa = self._albedo if cos_i.ndim == 1 else self._albedo[:, None, :]
        return _factor_at(fa, cos_i[..., None])

    def kernel(self):
        """:meth:`factor` on Dr.Jit arrays, for a wavefront of samples: a function of each sample's vertex
        (``mi.UInt32``) and cosine (``mi.Float``) returning F per channel (``mi.Color3f``), bilinear in
        the same table (single precision)."""
        return _FactorKernel(self._albedo)

    def at(self, vertices) -> HalfSpaceIncidence:
        """The same law for a few of the vertices (indices)."""
        return HalfSpaceIncidence(self.reflectance[np.asarray(vertices)], both_ways=self.both_ways)

    def exit(self, cos_o: np.ndarray) -> np.ndarray | None:
        r""":math:`\pi L / M = F(\mu_o)/\langle F\rangle` per vertex and channel (V, 3) toward views at
        ``cos_o`` (V,) (clipped to ≥ 10⁻³: a vertex seen edge-on is drawn with the grazing value);
        None without ``both_ways``."""
        if not self.both_ways:
            return None
        mu = np.clip(np.asarray(cos_o, np.float64), 1e-3, 1.0)
        return incidence_factor(mu[:, None], self.reflectance) / cosine_mean(self.reflectance)


class _FactorKernel:
    """F(μ; R_1) of :func:`_factor_at` in a Dr.Jit wavefront: the table and each vertex's albedo
    coordinates (V, 3) held as Dr.Jit arrays, looked up by vertex index."""

    def __init__(self, albedo: np.ndarray):
        mi = mitsuba()
        _, F = _table()
        self.F = mi.Float(F.astype(np.float32).ravel())  # (A, M) row-major
        self.fa = mi.Float(np.asarray(albedo, np.float32).ravel())  # (V, 3) row-major
        self.M = F.shape[1]

    def __call__(self, v, cos):
        mi, dr = mitsuba(), drjit()
        M = self.M
        # the cosine's column: even in √μ, clamped below the last column
        fm = dr.minimum(dr.sqrt(dr.clip(cos, 0.0, 1.0)) * (M - 1), M - 1.000001)
        im = mi.UInt32(fm)
        tm = fm - mi.Float(im)
        out = []
        for c in range(3):  # each channel's albedo row, then bilinear in (row, column)
            fa = dr.gather(mi.Float, self.fa, v * 3 + c)
            ia = mi.UInt32(fa)
            ta = fa - mi.Float(ia)
            i00 = ia * M + im
            f00, f01 = dr.gather(mi.Float, self.F, i00), dr.gather(mi.Float, self.F, i00 + 1)
            f10, f11 = dr.gather(mi.Float, self.F, i00 + M), dr.gather(mi.Float, self.F, i00 + M + 1)
            f = (1 - ta) * ((1 - tm) * f00 + tm * f01) + ta * ((1 - tm) * f10 + tm * f11)
            out.append(dr.select(cos > 0, f, 0.0))
        return mi.Color3f(*out)


#: the incidence laws by name: the default every renderer draws, its ablation, the data's own (the last two
#: as transports of :mod:`translucency.experimental.incidence`)
INCIDENCE_LAWS = ("half-space", "half-space-in", "normal")


def incidence_law(name: str, reflectance, eta: float = 1.0):
    """The law ``name`` (:data:`INCIDENCE_LAWS`) for an object with per-vertex normal-incidence totals
    ``reflectance`` (V, 3) behind a boundary of index ``eta``.

    ``half-space`` (in and out) and ``half-space-in`` (the irradiance only) need the totals and an
    index-matched boundary; where either is missing the law is :class:`NormalIncidence` (a dielectric
    object keeps the Fresnel transmittance's ratio alone).
    """
    if name not in INCIDENCE_LAWS:
        raise TranslucencyError(f"incidence: {name!r} is not one of {', '.join(INCIDENCE_LAWS)}")
    if name == "normal" or reflectance is None or eta != 1.0:
        return NormalIncidence()
    return HalfSpaceIncidence(np.asarray(reflectance, np.float64), both_ways=name == "half-space")
