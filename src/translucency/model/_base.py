r"""What every reflectance model shares: incident points, tangent frames, α,
and the two evaluation shapes the fitter and the renderer need.

A model maps a pair :math:`(\vec x_i, \vec x_o)` to

.. math:: R_d(\vec x_i, \vec x_o) = \alpha(\vec x_o)\, P_i(r, \theta)

where :math:`P_i` is the model's *profile* at incident point ``i`` (the
empirical sum of exponentials, the dipole or the Burley profile),
:math:`r = |\vec x_o - \vec x_i|` in mm and :math:`\theta` the angle of
:math:`\vec x_o - \vec x_i` in the tangent frame at :math:`\vec x_i`.  Units:
positions in mm, :math:`R_d` in mm⁻² per unit incident power, RGB linear.
Subclasses implement :meth:`profile`, :meth:`energy_within` and
:meth:`total_reflectance`; everything else lives here once.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from .._validate import TranslucencyError, as_float_array, as_index_array, check_nonnegative, check_positive
from .alpha import Modulation, PlanarAlpha, VertexAlpha

#: channels of every profile (linear RGB)
N_CHANNELS = 3


class ReflectanceModel(ABC):
    """Base class: geometry of the incident points and the modulation texture.

    Parameters
    ----------
    x_i : array_like, shape (N, 2) or (N, 3)
        Incident points in mm: (x, y) on a planar sample, (x, y, z) on a mesh.
    alpha : PlanarAlpha or VertexAlpha
        Modulation texture :math:`\\alpha(\\vec x_o)`.
    frame : array_like, shape (N, 3, 3), optional
        Mesh only: rows are the tangent, bitangent and normal at each
        :math:`\\vec x_i` (orthonormal).  Planar samples use the global x and y
        axes as tangent and bitangent.

    Examples
    --------
    >>> from translucency.model import BurleyModel, PlanarAlpha
    >>> alpha = PlanarAlpha(np.full((4, 4), 2.0), (0.0, 0.0), 1.0)   # α = 2 everywhere
    >>> m = BurleyModel([[2.0, 2.0]], [[0.8, 0.8, 0.8]], [[2.0, 2.0, 2.0]], alpha)
    >>> isinstance(m, ReflectanceModel), m.geometry, m.n_points
    (True, 'planar', 1)
    >>> r, theta = m.polar(np.array([0]), np.array([[2.0, 3.0]]))   # 1 mm along +y: θ = π/2
    >>> float(r[0]), round(float(theta[0]), 4)
    (1.0, 1.5708)
    >>> # R_d = α(x_o) P_i(r, θ): twice the profile
    >>> bool(np.allclose(m.R_d([0], [[2.0, 3.0]]), 2 * m.profile(np.array([0]), r, theta)))
    True
    """

    kind: str = "abstract"

    #: mesh models: the surface's triangles (F, 3) over ``alpha.vertices``, so that a model renders on its own
    faces: np.ndarray | None = None
    #: mesh models: what the acquisition measured per incident point, (N, 3) each — ``own``: R_d averaged
    #: over the incident vertex's own area A_i (mm⁻², the pairs the fit excludes); ``total``: the diffuse
    #: exitance Σ_v A_v R_d(x_i, v) per unit incident power.  The renderer takes the near field and each
    #: kernel's total from them (:func:`translucency.transport.matrices.transport_matrices`).
    measured: dict | None = None
    #: the object the model describes (:mod:`translucency.model.extent`); None: α's support (a planar
    #: sample at least as large as its windows, a mesh's bounding box).  The fitters set it from the data
    #: set (a planar sample's size), a semi-infinite slab has none.
    extent = None
    #: photons per incident point of the photon tally the model was fitted to, if any: sets how far a
    #: total reflectance may exceed 1 by noise (:mod:`translucency.model.bounds`)
    tally_photons: int | None = None

    def __init__(self, x_i, alpha: Modulation, frame=None):
        x_i = as_float_array("x_i", x_i, ndim=2)
        if x_i.shape[1] not in (2, 3) or x_i.shape[0] == 0:
            raise TranslucencyError(f"x_i: expected shape (N, 2) or (N, 3) with N >= 1, got {x_i.shape}")
        if x_i.shape[1] == 2:
            if not isinstance(alpha, PlanarAlpha):
                raise TranslucencyError("alpha: a planar model (x_i of shape (N, 2)) needs a PlanarAlpha")
            if frame is not None:
                raise TranslucencyError("frame: planar models use the global axes; pass frame=None")
        else:
            if not isinstance(alpha, VertexAlpha):
                raise TranslucencyError("alpha: a mesh model (x_i of shape (N, 3)) needs a VertexAlpha")
            if frame is None:
                raise TranslucencyError(
                    "frame: a mesh model needs a tangent frame (N, 3, 3) per incident point"
                )
            frame = as_float_array("frame", frame, shape=(x_i.shape[0], 3, 3))
            gram = np.einsum("nij,nkj->nik", frame, frame)
            err = np.abs(gram - np.eye(3)).max(axis=(1, 2))
            if (err > 1e-3).any():
                i = int(np.argmax(err))
                raise TranslucencyError(f"frame: not orthonormal at incident point {i} (error {err[i]:.2g})")
        self.x_i = x_i
        self.alpha = alpha
        self.frame = frame

    # -- geometry -----------------------------------------------------------
    @property
    def n_points(self) -> int:
        """Number of incident points N."""
        return self.x_i.shape[0]

    @property
    def geometry(self) -> str:
        """``"planar"`` or ``"mesh"``."""
        return "planar" if self.x_i.shape[1] == 2 else "mesh"

    def polar(self, i: np.ndarray, x_o: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distance r (mm) and tangent-frame angle θ (rad) of x_o seen from x_i[i]."""
        v = x_o - self.x_i[i]
        r = np.sqrt(np.einsum("...j,...j->...", v, v))
        if self.frame is None:
            theta = np.arctan2(v[..., 1], v[..., 0])
        else:
            f = self.frame[i]
            theta = np.arctan2(
                np.einsum("...j,...j->...", v, f[..., 1, :]), np.einsum("...j,...j->...", v, f[..., 0, :])
            )
        return r, theta

    # -- evaluation ---------------------------------------------------------
    def R_d(self, i, x_o, *, alpha_o=None) -> np.ndarray:
        """:math:`R_d(\\vec x_i, \\vec x_o)` for arrays of pairs, in mm⁻².

        Parameters
        ----------
        i : array_like of int, shape (P,)
            Index of the incident point of each pair.
        x_o : array_like, shape (P, D)
            Outgoing positions in mm (D = 2 planar, 3 mesh).
        alpha_o : array_like, shape (P,), optional
            :math:`\\alpha(\\vec x_o)` if the caller already knows it (a
            renderer evaluating at vertices); looked up in the texture otherwise.

        Returns
        -------
        R_d : ndarray, shape (P, 3)
            Diffuse reflectance per unit incident power, linear RGB.
        """
        i = as_index_array("i", i, self.n_points)
        x_o = as_float_array("x_o", x_o, shape=i.shape + (self.x_i.shape[1],))
        r, theta = self.polar(i, x_o)
        a = self.alpha.at(x_o) if alpha_o is None else as_float_array("alpha_o", alpha_o, shape=i.shape)
        return a[..., None] * self.profile(i, r, theta)

    def R_d_window(self, i, origin, pitch: float, shape: tuple[int, int]) -> np.ndarray:
        """:math:`R_d` at every pixel centre of a window around each ``x_i[i]`` (planar only).

        Parameters
        ----------
        i : array_like of int, shape (B,)
            Incident points.
        origin : array_like, shape (B, 2)
            Corner (x, y) in mm of each window; pixel ``[row, col]`` is centred
            at ``origin + pitch * (col + 1/2, row + 1/2)``.
        pitch : float
            Pixel size in mm.
        shape : (H, W)
            Window size in pixels.

        Returns
        -------
        R_d : ndarray, shape (B, H, W, 3)
        """
        if self.geometry != "planar":
            raise TranslucencyError("R_d_window: windows exist on planar samples only")
        i = np.atleast_1d(as_index_array("i", i, self.n_points))
        origin = as_float_array("origin", origin, shape=(i.shape[0], 2))
        h, w = (int(s) for s in shape)
        col, row = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
        x_o = origin[:, None, None, :] + pitch * np.stack([col, row], axis=-1)[None]
        ii = np.broadcast_to(i[:, None, None], x_o.shape[:-1])
        r, theta = self.polar(ii, x_o)
        return self.alpha.at(x_o)[..., None] * self.profile(ii, r, theta)

    # -- model-specific ------------------------------------------------------
    @abstractmethod
    def profile(self, i: np.ndarray, r: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Profile :math:`P_i(r, \\theta)` without α, shape ``r.shape + (3,)``, mm⁻²."""

    @abstractmethod
    def energy_within(self, i: np.ndarray, radius: np.ndarray) -> np.ndarray:
        """:math:`\\int_{|x_o - x_i| < radius} P_i\\, dA` (without α), shape ``radius.shape + (3,)``."""

    def total_reflectance(self) -> np.ndarray:
        """:math:`\\int P_i\\, dA` over the plane for every incident point, shape (N, 3)."""
        i = np.arange(self.n_points)
        return self.energy_within(i, np.full(self.n_points, np.inf))

    def energy_beyond(self, distance: np.ndarray) -> np.ndarray:
        r"""Energy (without α) each profile places beyond an edge, shape (N, 3).

        ``distance`` (N, T): the edge's distance (mm, inf: none) from x_i along the T angles
        :math:`\theta_t = 2\pi (t + 1/2) / T` of the tangent frame.  For a radial profile the energy of the
        wedge dθ beyond R(θ) is (ρ − E(R(θ))) dθ / 2π, E the energy within a disk
        (:meth:`energy_within`): the mean over θ of ρ − E(R(θ)).
        """
        i = np.broadcast_to(np.arange(self.n_points)[:, None], distance.shape)
        total = self.total_reflectance()[:, None, :]
        finite = np.isfinite(distance)[..., None]
        within = self.energy_within(i, np.where(finite[..., 0], distance, 0.0))
        return np.where(finite, total - within, 0.0).mean(axis=1)

    def energy_radius(self, fraction: float = 0.999) -> np.ndarray:
        """Radius (mm) holding ``fraction`` of each point's energy, max over channels.

        This is the truncation radius of renderers and fitters.  Found by
        bisection on :meth:`energy_within` (closed form in every model).

        Returns
        -------
        radius : ndarray, shape (N,)
        """
        if not 0.0 < fraction < 1.0:
            raise TranslucencyError(f"fraction: must lie in (0, 1), got {fraction}")
        i = np.arange(self.n_points)
        return bisect_radius(lambda rad: self.energy_within(i, rad), self.total_reflectance(), fraction)

    # -- storage (what a model file holds: translucency.io.model_file) -------
    #: the parameter arrays a model file stores as ``params/<name>``, in file order
    STORED: tuple = ()

    def stored(self) -> dict:
        """The parameter arrays to store, by name (None: the model has none of that name)."""
        return {name: getattr(self, name) for name in self.STORED}

    def header_fields(self) -> dict:
        """The model file header's fields of this kind (besides those every model has)."""
        return {}

    @classmethod
    def required_params(cls, header: dict) -> tuple:
        """The parameter arrays a model file of this kind must hold (``header``: the file's)."""
        return cls.STORED

    @classmethod
    def from_stored(cls, x_i, params: dict, alpha: Modulation, frame, header: dict) -> ReflectanceModel:
        """The model from a file's arrays: ``params`` by name (None where absent) and its header."""
        raise TypeError(f"{cls.__name__} declares no model-file storage: it cannot be read from a model file")

    @staticmethod
    def store_inert(params: dict, over: dict, points: list) -> bool:
        """Make the values that overflow float32 inert (zero reflectance) in ``params`` (float64 copies,
        changed in place; ``over``: per parameter, (N,) bool of the points that overflow, ``points``
        their indices); False when the kind has no inert setting (the file is refused)."""
        return False

    @property
    def param_shape(self) -> tuple:
        """The stored parameters of one incident point, as a shape (for the memory estimates)."""
        return (sum(int(np.prod(np.shape(v)[1:])) for v in self.stored().values() if v is not None),)

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.geometry}, {self.n_points} incident points>"


def bisect_radius(energy_within, total: np.ndarray, fraction: float, iters: int = 64) -> np.ndarray:
    """Smallest radius with ``energy_within(radius) >= fraction * total`` in every channel.

    Parameters
    ----------
    energy_within : callable
        Maps radii of shape (N,) to enclosed energy of shape (N, C); increasing.
    total : ndarray, shape (N, C)
        Enclosed energy at infinity.
    fraction : float
        Target fraction in (0, 1).
    """
    target = fraction * total
    n = total.shape[0]

    def short(rad):  # True where some channel still holds less than the target
        return (energy_within(rad) < target).any(axis=-1)

    lo, hi = np.zeros(n), np.ones(n)
    for _ in range(200):  # grow the bracket geometrically
        grow = short(hi)
        if not grow.any():
            break
        lo = np.where(grow, hi, lo)
        hi = np.where(grow, 2.0 * hi, hi)
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        s = short(mid)
        lo, hi = np.where(s, mid, lo), np.where(s, hi, mid)
    return hi


def medium_parameters(n_points: int, sigma_a, sigma_s_prime, eta):
    """The per-point medium of the physically based baselines, checked: σ_a ≥ 0 and σ_s' > 0 (N, 3) in
    mm⁻¹, and the boundary's relative index η > 0.  Returns (sigma_a, sigma_s_prime, eta)."""
    shape = (n_points, N_CHANNELS)
    sigma_a = as_float_array("sigma_a", sigma_a, shape=shape)
    sigma_s_prime = as_float_array("sigma_s_prime", sigma_s_prime, shape=shape)
    check_nonnegative("sigma_a", sigma_a)
    check_positive("sigma_s_prime", sigma_s_prime)
    eta = float(as_float_array("eta", eta, ndim=0))
    if not eta > 0:
        raise TranslucencyError(f"eta: must be > 0, got {eta}")
    return sigma_a, sigma_s_prime, eta


class MediumStorage:
    """The storage of the models of (σ_a, σ_s') per point and channel (mm⁻¹) and a global η
    (the dipole, PBD and the directional dipole): the two arrays, η in the header."""

    STORED = ("sigma_a", "sigma_s_prime")

    def header_fields(self) -> dict:
        return {"eta": self.eta}

    @classmethod
    def from_stored(cls, x_i, params, alpha, frame, header):
        return cls(x_i, params["sigma_a"], params["sigma_s_prime"], header["eta"], alpha, frame=frame)
