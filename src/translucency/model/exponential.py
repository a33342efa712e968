r"""The empirical model of Fuchs et al., eq. (1):

.. math::

   R_d(\vec x_i, \vec x_o) = \alpha(\vec x_o) \sum_{l=1}^{m} w_l(\vec x_i, \vec x_o)
   \begin{pmatrix} 1 \\ s_g(\vec x_i) \\ s_b(\vec x_i) \end{pmatrix}
   \sum_{k=1}^{n} c_{kl}(\vec x_i)\, e^{d_{kl}(\vec x_i)\, |\vec x_o - \vec x_i|}

with eq. (2), :math:`R_d \to 0` as :math:`r \to \infty`, enforced as
:math:`d_{kl} < 0` and :math:`c_{kl} \ge 0`.  Units: :math:`c` in mm⁻²,
:math:`d` in mm⁻¹, :math:`r` in mm, :math:`s_g, s_b` dimensionless.

Parameters are stored as ``c, d`` of shape ``(N, C, m, n)``: N incident
points, C colour blocks, m directions, n terms.  ``C = 1`` is the paper's
*shared* fall-off scaled by :math:`(1, s_g, s_b)`; ``C = 3`` is our
*per-channel* extension with separate c, d for R, G and B (no colour scale).

Closed forms used below, with :math:`a = -d > 0`:

* radial energy of one term, :math:`\int_0^R r\, e^{-a r} dr = \bigl(1 - e^{-aR}(1 + aR)\bigr)/a^2`;
* each direction weight integrates to :math:`2\pi/m` over the circle, so the
  total diffuse reflectance is :math:`\frac{2\pi}{m}\sum_l\sum_k c_{kl}/d_{kl}^2`
  (:math:`2\pi \sum_k c_k/d_k^2` for the isotropic model);
* in area measure, one term is a Gamma(2, 1/a) density in r times the hat
  :math:`w_l` in θ, so the whole model is a mixture that is sampled exactly.
"""

from __future__ import annotations

import numpy as np

from .._validate import TranslucencyError, as_float_array, as_index_array
from ._base import N_CHANNELS, ReflectanceModel, bisect_radius
from .alpha import Modulation
from .directions import TWO_PI, direction_angles, direction_weights, sample_direction_offset


def _check_eq2(c: np.ndarray, d: np.ndarray) -> None:
    """Eq. (2): every d < 0 and every c >= 0; the error names point and parameter."""
    for name, bad in (("d", ~(d < 0)), ("c", ~(c >= 0))):
        if bad.any():
            p, ch, l, k = (int(v) for v in np.argwhere(bad)[0])
            val = (d if name == "d" else c)[p, ch, l, k]
            need = "< 0" if name == "d" else ">= 0"
            raise TranslucencyError(
                f"eq. (2) violated at incident point {p}: {name}[channel block {ch}, direction {l}, "
                f"term {k}] = {val:g}, must be {need}"
            )


class ExponentialModel(ReflectanceModel):
    """The sum-of-exponentials model of eq. (1), isotropic (m = 1) or anisotropic.

    Parameters
    ----------
    x_i : array_like, shape (N, 2) or (N, 3)
        Incident points in mm.
    c : array_like, shape (N, C, m, n)
        Term amplitudes :math:`c_{kl}(\\vec x_i)` in mm⁻², >= 0.
    d : array_like, shape (N, C, m, n)
        Term exponents :math:`d_{kl}(\\vec x_i)` in mm⁻¹, < 0.
    alpha : PlanarAlpha or VertexAlpha
        Modulation texture.
    s_g, s_b : array_like, shape (N,), optional
        Colour scales; required when C = 1 (shared fall-off), forbidden when C = 3.
    frame : array_like, shape (N, 3, 3), optional
        Tangent frames (mesh models only).

    Examples
    --------
    >>> import numpy as np
    >>> from translucency.model import ExponentialModel, PlanarAlpha
    >>> c = np.array([[[[0.5, 0.1, 0.01]]]]); d = np.array([[[[-4.0, -1.5, -0.6]]]])
    >>> m = ExponentialModel([[0.0, 0.0]], c, d, PlanarAlpha.uniform((8, 8), (-2, -2), 0.5),
    ...                      s_g=[0.8], s_b=[0.6])
    >>> m.total_reflectance().round(4)   # 2π Σ c/d² × (1, s_g, s_b)
    array([[0.6501, 0.5201, 0.3901]])
    """

    kind = "exponential"

    def __init__(self, x_i, c, d, alpha: Modulation, *, s_g=None, s_b=None, frame=None):
        super().__init__(x_i, alpha, frame)
        c = as_float_array("c", c, ndim=4)
        d = as_float_array("d", d, shape=c.shape)
        n_pts, n_col, m, n = c.shape
        if n_pts != self.n_points:
            raise TranslucencyError(f"c: {n_pts} incident points, but x_i has {self.n_points}")
        if n_col not in (1, N_CHANNELS) or m < 1 or n < 1:
            raise TranslucencyError(f"c: expected shape (N, 1 or 3, m >= 1, n >= 1), got {c.shape}")
        _check_eq2(c, d)
        if n_col == 1:
            if s_g is None or s_b is None:
                raise TranslucencyError("s_g, s_b: the shared-colour model (C = 1) needs both colour scales")
            s_g = as_float_array("s_g", s_g, shape=(n_pts,))
            s_b = as_float_array("s_b", s_b, shape=(n_pts,))
            for name, s in (("s_g", s_g), ("s_b", s_b)):
                if (s < 0).any():
                    p = int(np.argmax(s < 0))
                    raise TranslucencyError(f"{name}: negative colour scale {s[p]:g} at incident point {p}")
        elif s_g is not None or s_b is not None:
            raise TranslucencyError("s_g, s_b: the per-channel model (C = 3) has no colour scales")
        self.c, self.d, self.s_g, self.s_b = c, d, s_g, s_b

    # -- storage ----------------------------------------------------------------
    STORED = ("c", "d", "s_g", "s_b")

    def header_fields(self) -> dict:
        return {"n_terms": self.n_terms, "n_directions": self.n_directions, "colour": self.colour}

    @classmethod
    def required_params(cls, header):
        return cls.STORED if header.get("colour") == "shared" else ("c", "d")

    @classmethod
    def from_stored(cls, x_i, params, alpha, frame, header):
        return cls(x_i, params["c"], params["d"], alpha, s_g=params["s_g"], s_b=params["s_b"], frame=frame)

    @staticmethod
    def store_inert(params, over, points):
        """Terms beyond float32 become c = 0, d = −1 mm⁻¹; a colour scale beyond it makes its point inert."""
        c, d = params["c"], params["d"]
        with np.errstate(over="ignore", invalid="ignore"):
            term = ~(np.isfinite(c.astype(np.float32)) & np.isfinite(d.astype(np.float32)))
        for scale in ("s_g", "s_b"):  # a colour scale beyond float32: the whole point is inert
            if params[scale] is not None:
                whole = over[scale]
                term[whole] = True
                params[scale][whole] = 1.0
        c[term], d[term] = 0.0, -1.0
        return True

    @property
    def param_shape(self) -> tuple:
        return tuple(self.c.shape[1:]) + (2,)

    # -- shape ----------------------------------------------------------------
    @property
    def n_terms(self) -> int:
        """n, the number of exponential terms."""
        return self.c.shape[3]

    @property
    def n_directions(self) -> int:
        """m, the number of directions (1 = isotropic)."""
        return self.c.shape[2]

    @property
    def colour(self) -> str:
        """``"shared"`` (paper: fall-off scaled by (1, s_g, s_b)) or ``"per-channel"``."""
        return "shared" if self.c.shape[1] == 1 else "per-channel"

    @property
    def colour_scale(self) -> np.ndarray:
        """:math:`(1, s_g, s_b)` per point, shape (N, 3); ones for per-channel models."""
        if self.s_g is None:
            return np.ones((self.n_points, N_CHANNELS))
        return np.stack([np.ones(self.n_points), self.s_g, self.s_b], axis=1)

    def _expand(self, x: np.ndarray) -> np.ndarray:
        """Broadcast a (..., C, ...) array over the three channels."""
        return np.broadcast_to(x, x.shape[:1] + (N_CHANNELS,) + x.shape[2:])

    # -- eq. (1) --------------------------------------------------------------
    def profile(self, i, r, theta) -> np.ndarray:
        """Eq. (1) without α: :math:`\\sum_l w_l (1, s_g, s_b) \\sum_k c_{kl} e^{d_{kl} r}`.

        Parameters
        ----------
        i : ndarray of int, shape (...)
            Incident point per sample.
        r : ndarray, shape (...)
            Distance in mm.
        theta : ndarray, shape (...)
            Angle in the tangent frame at x_i, radians.

        Returns
        -------
        P : ndarray, shape (..., 3), mm⁻²
        """
        # Σ_k c_kl exp(d_kl r): shape (..., C, m)
        per_dir = np.einsum("...clk,...clk->...cl", self.c[i], np.exp(self.d[i] * r[..., None, None, None]))
        # Σ_l w_l (...): shape (..., C)
        w = direction_weights(theta, self.n_directions)
        blended = np.einsum("...cl,...l->...c", per_dir, w)
        return blended * self.colour_scale[i]

    # -- closed forms -----------------------------------------------------------
    def _term_energy(self, i, radius) -> np.ndarray:
        """(2π/m) c (1 - e^{-aR}(1 + aR)) / a² per term, shape radius.shape + (C, m, n)."""
        a = -self.d[i]
        aR = a * radius[..., None, None, None]
        at_inf = np.isinf(aR)
        aR = np.where(at_inf, 0.0, aR)
        inside = np.where(at_inf, 1.0, -np.expm1(-aR) - aR * np.exp(-aR))
        return (TWO_PI / self.n_directions) * self.c[i] * inside / a**2

    def energy_within(self, i, radius) -> np.ndarray:
        """Energy of eq. (1) (without α) inside a disk of ``radius`` mm around x_i, shape (..., 3)."""
        i = np.asarray(i)
        radius = np.broadcast_to(np.asarray(radius, dtype=np.float64), i.shape)
        return self._term_energy(i, radius).sum(axis=(-1, -2)) * self.colour_scale[i]

    def energy_beyond(self, distance: np.ndarray) -> np.ndarray:
        r"""Energy of eq. (1) (without α) beyond an edge at ``distance`` (N, T) mm along the angles
        θ_t = 2π(t + ½)/T, shape (N, 3) (see :meth:`ReflectanceModel.energy_beyond`).

        Closed form in r: :math:`\int_R^\infty c e^{-a r} r\, dr = c\, e^{-aR}(1 + aR) / a^2` per term,
        blended over the directions by :math:`w_l(\theta_t)` and averaged over θ (× 2π).
        """
        T = distance.shape[1]
        w = direction_weights(TWO_PI * (np.arange(T) + 0.5) / T, self.n_directions)  # (T, m)
        out = np.zeros((self.n_points, self.c.shape[1]))
        for s in range(0, self.n_points, 64):  # blocks of points: (64, T, C, m, n) at a time
            a, c = -self.d[s : s + 64, None], self.c[s : s + 64, None]
            aR = np.minimum(a * distance[s : s + 64, :, None, None, None], 1e3)  # inf: no energy beyond
            tail = np.sum(c * np.exp(-aR) * (1.0 + aR) / a**2, axis=-1)  # (k, T, C, m)
            out[s : s + 64] = TWO_PI * np.einsum("ktcm,tm->kc", tail, w) / T
        return out * self.colour_scale  # (N, C) broadcast over the channels, times (1, s_g, s_b)

    def direction_totals(self) -> np.ndarray:
        r"""Each direction's own total :math:`2\pi \sum_k c_{lk} / d_{lk}^2` (the total of a point whose
        profile were direction l's all round), shape (N, 3, m); their mean over l is the total."""
        own = TWO_PI * np.sum(self.c / self.d**2, axis=-1)  # (N, C, m)
        return self._expand(own) * self.colour_scale[:, :, None]

    def energy_radius(self, fraction: float = 0.999) -> np.ndarray:
        """Truncation radius in mm: the largest, over channels *and directions*,
        radius holding ``fraction`` of that direction's radial energy.

        Taking the maximum over directions keeps the longest-reaching direction
        of an anisotropic model inside the radius; for m = 1 this is the radius
        of the disk holding ``fraction`` of the total.
        """
        if not 0.0 < fraction < 1.0:
            raise TranslucencyError(f"fraction: must lie in (0, 1), got {fraction}")
        i = np.arange(self.n_points)

        def per_direction(radius):  # (N, C*m): enclosed energy of each direction's profile
            e = self._term_energy(i, radius).sum(axis=-1)
            return e.reshape(self.n_points, -1)

        return bisect_radius(per_direction, per_direction(np.full(self.n_points, np.inf)), fraction)

    # -- exact importance sampling ------------------------------------------------
    def _mixture(self, i: int, channel: int | None):
        """Component weights (flattened over channel, direction, term) and rates a = -d."""
        a = -self._expand(self.d[i : i + 1])[0]  # (3, m, n)
        energy = self._expand(self.c[i : i + 1])[0] / a**2 * self.colour_scale[i][:, None, None]
        if channel is not None:
            mask = np.zeros(N_CHANNELS, dtype=bool)
            mask[channel] = True
            energy = np.where(mask[:, None, None], energy, 0.0)
        total = energy.sum()
        if not total > 0:
            raise TranslucencyError(f"sample: incident point {i} has zero energy; nothing to sample")
        return energy.ravel() / total, a.ravel()

    def sample(self, i: int, u, channel: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Sample an exit point around x_i exactly in proportion to eq. (1).

        The estimator's density in area measure around x_i is
        :math:`p(r, \\theta) = P_i(r, \\theta) / \\int P_i\\, dA` for the chosen
        ``channel`` (or the sum of the three channels when ``None``): pick a
        term (channel, l, k) with probability :math:`\\propto s\\, c_{kl} /
        d_{kl}^2`, draw :math:`r \\sim \\mathrm{Gamma}(2, -1/d_{kl})` (the radial
        density :math:`a^2 r e^{-ar}` already contains the area Jacobian) and
        :math:`\\theta` from the hat :math:`w_l`.

        Parameters
        ----------
        i : int
            Incident point.
        u : array_like, shape (S, 4)
            Uniform numbers in [0, 1).
        channel : {0, 1, 2, None}
            Channel whose profile is the target density; ``None`` for their sum.

        Returns
        -------
        r, theta : ndarray, shape (S,)
            Distance in mm and tangent-frame angle in radians.

        Examples
        --------
        >>> from translucency.model import PlanarAlpha
        >>> m = ExponentialModel([[0, 0]], [[[[1.0]]]], [[[[-2.0]]]],
        ...                      PlanarAlpha.uniform((1, 1)), s_g=[1.0], s_b=[1.0])
        >>> r, _ = m.sample(0, np.random.default_rng(0).random((100000, 4)))
        >>> round(float(r.mean()), 2)  # Gamma(2, 1/2) has mean 1
        1.0
        """
        i = int(as_index_array("i", np.asarray(i), self.n_points))
        u = as_float_array("u", u, shape=(None, 4))
        weights, a = self._mixture(i, channel)
        comp = np.minimum(np.searchsorted(np.cumsum(weights), u[:, 0], side="right"), weights.size - 1)
        # Gamma(2, 1/a) = sum of two exponentials
        r = -(np.log1p(-u[:, 1]) + np.log1p(-u[:, 2])) / a[comp]
        direction = (comp // self.n_terms) % self.n_directions
        theta = direction_angles(self.n_directions)[direction] + sample_direction_offset(
            u[:, 3], self.n_directions
        )
        return r, np.mod(theta, TWO_PI)

    def pdf(self, i: int, r, theta, channel: int | None = None) -> np.ndarray:
        """Density of :meth:`sample` in area measure (mm⁻²) at (r, θ) around x_i."""
        i = int(as_index_array("i", np.asarray(i), self.n_points))
        r = np.asarray(r, dtype=float)
        theta = np.broadcast_to(np.asarray(theta, dtype=float), r.shape)
        ii = np.full(r.shape, i)
        p = self.profile(ii, r, theta)
        tot = self.total_reflectance()[i]
        if channel is None:
            return p.sum(axis=-1) / tot.sum()
        return p[..., channel] / tot[channel]
