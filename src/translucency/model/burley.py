r"""Normalized diffusion of Christensen and Burley (2015).

.. math:: R(r) = A\, s\, \frac{e^{-s r} + e^{-s r/3}}{8\pi r}

with surface albedo A (dimensionless) and shape parameter s (mm⁻¹).  The
profile integrates to A over the plane, and the enclosed energy is closed form,

.. math:: \int_0^R 2\pi r R(r)\,dr = A\Bigl(1 - \tfrac14 e^{-sR} - \tfrac34 e^{-sR/3}\Bigr),

so in area measure :math:`2\pi r R / A` is the mixture
:math:`\tfrac14\,\mathrm{Exp}(s) + \tfrac34\,\mathrm{Exp}(s/3)` in r, sampled exactly.

:func:`burley_shape` gives the authors' fits of s to Monte Carlo references
for the three configurations of their paper, in units of the mean free path
:math:`\ell` (or the diffuse mean free path :math:`\ell_d`).
"""

from __future__ import annotations

import numpy as np

from .._validate import TranslucencyError, as_float_array, as_index_array, check_nonnegative, check_positive
from ._base import N_CHANNELS, ReflectanceModel
from .alpha import Modulation
from .directions import TWO_PI

#: R(r) diverges as 1/r at the incident point; profiles are evaluated at max(r, R_MIN) mm.
R_MIN = 1e-4


def burley_R(r, A, s) -> np.ndarray:
    """Burley's normalized diffusion profile in mm⁻² at distance r (mm).

    Examples
    --------
    >>> # A s (e^{-2} + e^{-2/3}) / (8π) with A = 0.8, s = 2
    >>> round(float(burley_R(1.0, 0.8, 2.0)), 4)
    0.0413
    """
    r = np.maximum(np.asarray(r, dtype=np.float64), R_MIN)
    return A * s * (np.exp(-s * r) + np.exp(-s * r / 3.0)) / (8.0 * np.pi * r)


def burley_energy_within(radius, A, s) -> np.ndarray:
    """Closed-form :math:`\\int_0^R 2\\pi r R(r)\\,dr`; R may be ``inf``.

    Examples
    --------
    >>> burley_energy_within([0.0, 1.0, np.inf], 0.8, 2.0).round(4)   # 0 at R = 0, the albedo A at R = ∞
    array([0.    , 0.4649, 0.8   ])
    """
    sR = s * np.asarray(radius, dtype=np.float64)
    return A * (1.0 - 0.25 * np.exp(-sR) - 0.75 * np.exp(-sR / 3.0))


def burley_shape(A, mean_free_path, config: str = "searchlight") -> np.ndarray:
    """Shape parameter s (mm⁻¹) from albedo A and a mean free path (mm).

    Christensen & Burley (2015) fitted the scaling factor :math:`\\tilde s(A)`
    to Monte Carlo references; then :math:`s = \\tilde s / \\ell`.

    ``config``:
      * ``"searchlight"`` (normal incidence, mean free path): :math:`\\tilde s = 1.85 - A + 7|A - 0.8|^3`
      * ``"diffuse"`` (diffuse transmission, mean free path): :math:`\\tilde s = 1.9 - A + 3.5(A - 0.8)^2`
      * ``"dmfp"`` (diffuse mean free path :math:`\\ell_d`): :math:`\\tilde s = 3.5 + 100(A - 0.33)^4`

    Examples
    --------
    >>> float(burley_shape(0.8, 1.0))   # searchlight at A = 0.8: 1.85 − 0.8 per 1 mm mean free path
    1.05
    >>> float(burley_shape(0.8, 2.0))   # s scales as 1/ℓ
    0.525
    """
    A = np.asarray(A, dtype=np.float64)
    if config == "searchlight":
        scale = 1.85 - A + 7.0 * np.abs(A - 0.8) ** 3
    elif config == "diffuse":
        scale = 1.9 - A + 3.5 * (A - 0.8) ** 2
    elif config == "dmfp":
        scale = 3.5 + 100.0 * (A - 0.33) ** 4
    else:
        raise TranslucencyError(f"config: expected 'searchlight', 'diffuse' or 'dmfp', got {config!r}")
    return scale / np.asarray(mean_free_path, dtype=np.float64)


#: profiles reduced at once by :func:`burley_of_exponentials` (its temporaries: 64 radii x n terms x 8
#: bytes a profile, about 100 MB each for 3 terms)
BURLEY_BLOCK = 1 << 16


def burley_of_exponentials(c, d, radii: int = 64):
    r"""The Christensen–Burley profile that matches a sum of exponentials :math:`\sum_k c_k e^{d_k r}` in
    energy and mean radius, and how far it is from it.

    Energy :math:`A = 2\pi \sum_k c_k/d_k^2`; mean radius (area measure)
    :math:`\langle r\rangle = \sum_k 4\pi c_k/|d_k|^3 / A`; Burley's is :math:`2.5/s`, so
    :math:`s = 2.5/\langle r\rangle`.  The error compares the energy within radius r (Burley's 1/r peak
    makes a pointwise L2 distance infinite): the RMS over ``radii`` radii up to four mean radii of
    :math:`(E_B(r) - E(r))/A`, with :math:`E(r) = \sum_k 2\pi c_k (1 + (d_k r - 1) e^{d_k r})/d_k^2` and
    Burley's closed form (:func:`burley_energy_within`).

    Parameters
    ----------
    c, d : ndarray, shape (..., n)
        Amplitudes (mm⁻²) and rates (mm⁻¹, < 0) of the terms.

    Returns
    -------
    A, s, error : ndarray, shape (...)

    Examples
    --------
    >>> A, s, err = burley_of_exponentials(np.array([1.0]), np.array([-2.0]))
    >>> round(float(A), 4), round(float(s), 4)  # 2π/4, 2.5 over the mean radius 2/2 = 1 mm
    (1.5708, 2.5)
    """
    c = np.asarray(c, dtype=np.float64)
    d = np.asarray(d, dtype=np.float64)
    c, d = np.broadcast_arrays(c, d)
    shape, n = c.shape[:-1], c.shape[-1]
    c, d = c.reshape(-1, n), d.reshape(-1, n)
    out = np.empty((3, len(c)))
    # in blocks of BURLEY_BLOCK profiles: the energies within ``radii`` radii are (profiles, radii, n)
    for start in range(0, len(c), BURLEY_BLOCK):
        block = slice(start, start + BURLEY_BLOCK)
        out[:, block] = _burley_block(c[block], d[block], radii)
    A, s, error = (v.reshape(shape) for v in out)
    return A, s, error


def _burley_block(c: np.ndarray, d: np.ndarray, radii: int):
    """:func:`burley_of_exponentials` of profiles (P, n): (A, s, error), (P,) each."""
    A = TWO_PI * np.sum(c / d**2, axis=-1)
    first = 2.0 * TWO_PI * np.sum(c / np.abs(d) ** 3, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        mean_r = np.where(A > 0, first / A, np.nan)
        s = 2.5 / mean_r
    r = (np.arange(radii) + 0.5) / radii * 4.0 * np.nan_to_num(mean_r, nan=1.0)[..., None]  # (..., radii)
    dr = d[..., None, :] * r[..., :, None]
    E = np.sum(TWO_PI * c[..., None, :] * (1.0 + (dr - 1.0) * np.exp(dr)) / d[..., None, :] ** 2, axis=-1)
    E_b = burley_energy_within(r, A[..., None], s[..., None])
    with np.errstate(divide="ignore", invalid="ignore"):
        error = np.sqrt(np.mean((E_b - E) ** 2, axis=-1)) / A
    return A, s, error


class BurleyModel(ReflectanceModel):
    """Christensen–Burley profile per incident point, with a modulation texture.

    Parameters
    ----------
    x_i : array_like, shape (N, 2) or (N, 3)
        Incident points in mm.
    A : array_like, shape (N, 3)
        Albedo per point and channel (the profile's integral), >= 0.
    s : array_like, shape (N, 3)
        Shape parameter per point and channel, mm⁻¹, > 0.
    alpha : PlanarAlpha or VertexAlpha
        Modulation texture.

    Examples
    --------
    >>> from translucency.model import BurleyModel, PlanarAlpha
    >>> m = BurleyModel([[0.0, 0.0]], [[0.8, 0.6, 0.4]], [[2.0, 2.0, 2.0]], PlanarAlpha.uniform((8, 8)))
    >>> m.total_reflectance()   # the profile integrates to the albedo A
    array([[0.8, 0.6, 0.4]])
    >>> m.energy_within([0], [1.0]).round(4)   # within 1 mm: A (1 − e^{-2}/4 − 3 e^{-2/3}/4)
    array([[0.4649, 0.3487, 0.2324]])
    """

    kind = "burley"

    def __init__(self, x_i, A, s, alpha: Modulation, *, frame=None):
        super().__init__(x_i, alpha, frame)
        shape = (self.n_points, N_CHANNELS)
        A = as_float_array("A", A, shape=shape)
        s = as_float_array("s", s, shape=shape)
        check_nonnegative("A", A)
        check_positive("s", s)
        self.A, self.s = A, s

    STORED = ("A", "s")

    @classmethod
    def from_stored(cls, x_i, params, alpha, frame, header):
        return cls(x_i, params["A"], params["s"], alpha, frame=frame)

    @staticmethod
    def store_inert(params, over, points):
        for i in points:  # A = 0: no reflectance
            params["A"][i], params["s"][i] = 0.0, 1.0
        return True

    def profile(self, i, r, theta) -> np.ndarray:
        """Burley :math:`R(r)` per channel (θ unused); r clamped to ``R_MIN``."""
        return burley_R(r[..., None], self.A[i], self.s[i])

    def energy_within(self, i, radius) -> np.ndarray:
        i = np.asarray(i)
        radius = np.broadcast_to(np.asarray(radius, dtype=np.float64), i.shape)
        return burley_energy_within(radius[..., None], self.A[i], self.s[i])

    def sample(self, i: int, u, channel: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Exact sample of (r, θ) with density :math:`R(r)/A` in area measure.

        ``u`` has shape (S, 3): component choice, radius, angle.
        """
        i = int(as_index_array("i", np.asarray(i), self.n_points))
        u = as_float_array("u", u, shape=(None, 3))
        s = self.s[i, channel]
        rate = np.where(u[:, 0] < 0.25, s, s / 3.0)
        return -np.log1p(-u[:, 1]) / rate, TWO_PI * u[:, 2]
