r"""The medium of a measured object, estimated from its scan alone.

Per incident point i and channel, the pairs whose normals face the same way (:math:`n_i \cdot n_o > 1/2`)
within ``r_fit`` mm of the beam are summed in rings of distance,
:math:`E_b = \sum_{o \in b} A_o R_d(x_i, x_o)` over the ring's area :math:`A_b = \sum_{o \in b} A_o`
(mm², so :math:`E_b / A_b` in mm⁻²), and matched by the profile :math:`H(r) = \sigma_t^2 f(\sigma_t r;
\alpha)` of a homogeneous, index-matched, isotropically scattering half-space
(:mod:`translucency.model.half_space`), evaluated where the ring's vertices lie (:math:`r_b`, the
area-weighted geometric mean of their distances):

.. math:: \min_{\sigma_t,\,\alpha}\; \sum_b w_b \bigl(\log \tfrac{E_b}{A_b} - \log H(r_b)\bigr)^2
          + \Bigl(\log \sum_b E_b - \log \sum_b A_b H(r_b)\Bigr)^2,

:math:`w_b = E_b / \sum E` each ring's share of the measured energy, the second term the energy itself.
Then :math:`\sigma_s = \alpha \sigma_t` and :math:`\sigma_a = (1 - \alpha)\sigma_t` (mm⁻¹) at :math:`x_i`.

**The object's shape.**  A body is not a half-space: light that would spread through the half-space
below is held in by a curved or thin body, and the match alone reads that light as less absorption.  So
the estimate is scanned on the object itself (``rounds`` times, :func:`~.scan.virtual_scan`: the
acquisition's beams walked through it) and each ring is corrected by what the shape did to it,
:math:`G_b = S_b / (A_b H(r_b))` (the scan's ring energy over the half-space's), the match repeated on
:math:`E_b / G_b`.

**What the data cannot tell apart, and what is assumed there.**  A pencil-beam scan of a half-space
determines the reduced coefficients :math:`\sigma_s' = \sigma_s (1 - g)` and :math:`\sigma_a`; g itself
shows only within a transport mean free path of the beam, where the pairs are fewest.  The estimate is
the *similar* medium: g = 0 and :math:`\sigma_s = \sigma_s'`.  The boundary is taken index-matched (the
table's); the data's own boundary is folded into the coefficients, so the estimate is the index-matched
medium that reproduces the scan (the renderer applies the boundary's Fresnel terms at entry and exit as
for every transport).  Weak absorption, whose diffusion length :math:`1/\sqrt{3\sigma_a\sigma_t'}` exceeds
the rings' reach, is seen only in part and comes out low.  Inside the body the coefficients are those of
the nearest incident points, blended by inverse squared distance (:meth:`Medium.at`): the estimate resolves
the body's heterogeneity at the spacing of the incident points along the surface, and not at all in depth
(a layer under the surface is seen as the surface's mean).

The estimate reads the measured R_d, the mesh and the incident points, never the data set's record of
what fills it (its header's ``sample``, ``g`` or request): a lab's object has none.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree
from scipy.special import logsumexp

from .._validate import TranslucencyError
from ..acquire.volume import Volume
from ..geometry import vertex_areas
from ..model.half_space import half_space_table as _table
from .scan import virtual_scan

#: what the estimate assumes where the data cannot tell (module docstring), as info and evaluate say it
ASSUMED = "g = 0 assumed (similar medium), index-matched"
#: rings of distance the profile is matched on, from the exclusion radius to ``r_fit``
RINGS = 16
#: the farthest ring, mm (the bands of the scan the estimate is checked on run to 16 mm)
R_FIT = 16.0
#: pairs count as the beam's own side where n_i · n_o exceeds this
SAME_SIDE = 0.5
#: the lit rings a point needs for its own estimate (fewer: its nearest neighbours')
MIN_RINGS = 3
#: the extinction grid searched, mm⁻¹ (log-spaced)
SIGMA_T_GRID = np.geomspace(0.01, 200.0, 241)
#: albedos searched: the table's own and 7 between each two, in log(1 − α)
ALBEDO_STEPS = 8
#: incident points blended into each point of the body (:meth:`Medium.at`)
BLEND = 4
#: virtual scans that correct the half-space's rings for the object's shape (:func:`estimate_medium`)
ROUNDS = 2
#: photons per point and channel of each of them
SCAN_PHOTONS = 1000
#: voxels along the longest side of the grid a walk reads (:meth:`Medium.volume`)
VOXELS = 48


@dataclass(frozen=True, eq=False)
class Medium:
    """Per incident point, the similar medium (g = 0) that reproduces the scan around it.

    Parameters
    ----------
    x : ndarray, shape (P, 3)
        The incident points, mm.
    sigma_s, sigma_a : ndarray, shape (P, 3)
        Scattering and absorption coefficients at each, mm⁻¹ (RGB).
    residual : ndarray, shape (P, 3), optional
        The fit's RMS log residual over the rings at each point and channel (how well one half-space
        matches the scan there).

    Examples
    --------
    >>> m = Medium(np.zeros((1, 3)), np.full((1, 3), 2.0), np.full((1, 3), 0.01))
    >>> s, a = m.at(np.array([[5.0, 0.0, 0.0]]))
    >>> s.round(3).tolist(), m.albedo.round(4).tolist()
    ([[2.0, 2.0, 2.0]], [[0.995, 0.995, 0.995]])
    """

    x: np.ndarray
    sigma_s: np.ndarray
    sigma_a: np.ndarray
    residual: np.ndarray | None = None
    g: float = 0.0

    def __post_init__(self):
        x = np.asarray(self.x, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != 3 or len(x) == 0:
            raise TranslucencyError(f"medium: x must be (P, 3) points, got {x.shape}")
        for name in ("sigma_s", "sigma_a"):
            a = np.asarray(getattr(self, name), dtype=np.float64)
            if a.shape != (len(x), 3):
                raise TranslucencyError(f"medium: {name} must be ({len(x)}, 3), got {a.shape}")
            if not (np.isfinite(a).all() and (a >= 0).all()):
                raise TranslucencyError(f"medium: {name} must be finite and >= 0")
            object.__setattr__(self, name, a)
        if not (self.sigma_s + self.sigma_a > 0).all():
            raise TranslucencyError("medium: an incident point has σ_t = 0 in some channel")
        object.__setattr__(self, "x", x)

    @property
    def sigma_t(self) -> np.ndarray:
        """Extinction σ_s + σ_a, mm⁻¹, (P, 3)."""
        return self.sigma_s + self.sigma_a

    @property
    def albedo(self) -> np.ndarray:
        """Single-scattering albedo σ_s / σ_t, (P, 3)."""
        return self.sigma_s / self.sigma_t

    def at(self, points) -> tuple[np.ndarray, np.ndarray]:
        """(σ_s, σ_a) at ``points`` (N, 3) mm: the ``BLEND`` nearest incident points' coefficients blended
        by inverse squared distance, (N, 3) each, mm⁻¹."""
        points = np.asarray(points, dtype=np.float64)
        k = min(BLEND, len(self.x))
        d, idx = cKDTree(self.x).query(points, k=k)
        d, idx = d.reshape(len(points), k), idx.reshape(len(points), k)
        w = 1.0 / np.maximum(d, 1e-6) ** 2
        w /= w.sum(axis=1, keepdims=True)
        blend = lambda a: np.einsum("nk,nkc->nc", w, a[idx])  # noqa: E731
        return blend(self.sigma_s), blend(self.sigma_a)

    def volume(self, mesh, *, voxels: int = VOXELS) -> Volume:
        """The estimate on a grid of cubic voxels over ``mesh``'s bounding box (``voxels`` along its longest
        side), as the photon walks read it (:mod:`translucency.acquire.mesh_walk`: z index 0 at the top),
        behind an index-matched boundary."""
        lo, hi = (np.asarray(b, dtype=np.float64) for b in mesh.bounds)
        vox = float((hi - lo).max()) / voxels
        n = np.maximum(np.ceil((hi - lo) / vox - 1e-9).astype(int), 1)  # (x, y, z)
        ix, iy, iz = (np.arange(k) + 0.5 for k in n)
        Z, Y, X = np.meshgrid(iz, iy, ix, indexing="ij")
        centres = np.stack([lo[0] + X * vox, lo[1] + Y * vox, hi[2] - Z * vox], axis=-1).reshape(-1, 3)
        s, a = self.at(centres)
        shape = (n[2], n[1], n[0], 3)
        return Volume(
            s.reshape(shape), a.reshape(shape), vox, self.g, 1.0, {"generator": "estimated from the scan"}
        )

    def summary(self) -> dict:
        """Ranges per channel (min, median, max) of σ_s, σ_a (mm⁻¹) and the albedo, as ``info`` states
        them."""
        out = {}
        for name, a in (("sigma_s", self.sigma_s), ("sigma_a", self.sigma_a), ("albedo", self.albedo)):
            out[name] = np.percentile(a, [0, 50, 100], axis=0).T.round(6).tolist()  # (3 channels, 3)
        if self.residual is not None:
            out["rings_rms_log_residual"] = float(np.sqrt(np.mean(self.residual**2)))
        out["g"] = self.g
        out["points"] = len(self.x)
        out["index_matched"] = True
        out["assumed"] = ASSUMED
        return out

    def stacked(self) -> np.ndarray:
        """(P, 2, 3): σ_s and σ_a per point, as a model file stores it (``measured/medium``)."""
        return np.stack([self.sigma_s, self.sigma_a], axis=1)


def medium_of(model) -> Medium | None:
    """The estimate a fitted per-vertex model carries (``measured/medium``), or None."""
    stack = (model.measured or {}).get("medium")
    if stack is None:
        return None
    return Medium(np.asarray(model.x_i, dtype=np.float64), stack[:, 0], stack[:, 1])


def estimate_medium(
    ds, *, points=None, r_fit: float = R_FIT, rounds: int = ROUNDS, photons: int = SCAN_PHOTONS, seed: int = 0
) -> Medium:
    """Estimate the medium of a mesh data set's object from its measured R_d (module docstring).

    Parameters
    ----------
    ds : MeshDataset
        An acquisition or a lab's imported photographs
        (:func:`translucency.io.mesh_dataset.open_mesh_dataset`).
    points : array_like of int, optional
        The incident points (rows of the data set) the estimate reads; default all.  The held-out check
        estimates from half the points and scans the others (``benchmarks/medium_held_out.py``).
    r_fit : float
        The farthest ring, mm.
    rounds : int
        Virtual scans of the estimate that correct the half-space's rings for the object's shape (module
        docstring); 0: the half-space's match alone.
    photons, seed : int
        Photons per point and channel of each virtual scan, and their seed (the estimate is a pure function
        of the data and these).

    Returns
    -------
    Medium

    Examples
    --------
    >>> import tempfile, trimesh
    >>> import numpy as np
    >>> import translucency as tl
    >>> from translucency.medium.estimate import estimate_medium
    >>> ball = trimesh.creation.icosphere(2, radius=4.0)
    >>> data = tl.acquire_mesh(ball, tempfile.mkdtemp() + "/ball.zarr", "homogeneous:marble", voxel_mm=1.0,
    ...                        points=4, photons=300, index_matched=True)
    >>> medium = estimate_medium(data)
    >>> np.shape(medium.summary()["sigma_a"]), bool(np.all(np.asarray(medium.summary()["sigma_a"]) >= 0))
    ((3, 3), True)
    """
    g = ds.group
    mesh = ds.mesh()
    v = np.asarray(mesh.vertices, dtype=np.float64)
    incident = np.asarray(g["incident"][...])
    rows = np.arange(len(incident)) if points is None else np.asarray(points, dtype=np.int64)
    if rows.size == 0:
        raise TranslucencyError("points: the estimate needs at least one incident point")
    r_min = 0.5 * float(np.mean(mesh.edges_unique_length))  # half an edge: the beam's own vertex left out
    edges = np.geomspace(r_min, max(float(r_fit), 4.0 * r_min), RINGS + 1)
    flags = g["flags"] if "flags" in g else None
    row = lambda k: g["R_d"][int(rows[k])]  # noqa: E731 — (V, 3) R_d of the k-th point read, mm⁻²
    flag = None if flags is None else (lambda k: flags[int(rows[k])])
    A_b, E_b, r_b, T = _measured_rings(mesh, incident[rows], edges, row, flag)
    G = np.ones_like(E_b)  # what the object's shape does to each ring, against the half-space
    G_T = np.ones_like(T)  # ... and to the point's whole exitance
    scene = None
    for step in range(rounds + 1):
        # each point's rings matched by the half-space, evaluated where the ring's vertices lie
        a_s, resid, H_b = np.full((len(rows), 3, 2), -1), np.zeros((len(rows), 3)), np.zeros_like(E_b)
        for k in range(len(rows)):
            grid = _profile_grid(r_b[k])
            for c in range(3):
                found = _match(grid, A_b[k], E_b[k, :, c] / G[k, :, c], T[k, c] / G_T[k, c])
                if found is None:  # too few lit rings: the nearest points' estimate, below
                    continue
                a, s_, resid[k, c] = found
                a_s[k, c] = a, s_
                H_b[k, :, c] = np.exp(grid[1][a, s_]) * A_b[k]
        a_s = _filled(a_s, v[incident[rows]])
        albedo, sigma_t = _albedos()[a_s[..., 0]], SIGMA_T_GRID[a_s[..., 1]]
        medium = Medium(v[incident[rows]], albedo * sigma_t, (1 - albedo) * sigma_t, resid)
        if step == rounds:
            return medium
        # the estimate scanned on the object itself: its rings over the half-space's give the shape's factor
        from ..mitsuba import mesh_scene  # Mitsuba loads only to walk

        scene = mesh_scene(mesh) if scene is None else scene
        R = virtual_scan(mesh, medium.volume(mesh), incident[rows], photons, seed=seed + step, scene=scene)
        _, S_b, _, S_T = _measured_rings(mesh, incident[rows], edges, R.__getitem__)
        G = np.where((S_b > 0) & (H_b > 0), S_b / np.maximum(H_b, 1e-300), 1.0)
        H_T = _half_space_totals()[a_s[..., 0]]  # (n, 3) the half-space's whole exitance at each match
        G_T = np.where(S_T > 0, S_T / H_T, 1.0)
    return medium


def _measured_rings(mesh, incident, edges, row, flag=None):
    """The rings of each incident vertex's own side: their areas (n, B) mm², the energies Σ A_o R_d
    (n, B, 3) of the rows ``row(k)`` ((V, 3) R_d, mm⁻²; ``flag(k)``: the pairs not measured, left out) and
    where their vertices lie, the area-weighted geometric mean of r (n, B) mm (the ring's geometric centre
    where it holds none); and each point's whole exitance Σ_o A_o R_d over every vertex (n, 3)."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    nrm = np.asarray(mesh.vertex_normals, dtype=np.float64)
    area = vertex_areas(mesh)
    B = len(edges) - 1
    A_b, E_b = np.zeros((len(incident), B)), np.zeros((len(incident), B, 3))
    r_b = np.tile(np.sqrt(edges[:-1] * edges[1:]), (len(incident), 1))
    T = np.zeros((len(incident), 3))
    for k, i in enumerate(incident):
        R = np.asarray(row(k), dtype=np.float64)
        r = np.linalg.norm(v - v[i], axis=1)
        ok = (nrm @ nrm[i] > SAME_SIDE) & (r >= edges[0]) & (r < edges[-1]) & np.isfinite(R).all(axis=1)
        if flag is not None:
            ok &= np.asarray(flag(k)) == 0
        b = np.digitize(r[ok], edges) - 1
        A_b[k] = np.bincount(b, area[ok], B)
        log_r = np.bincount(b, area[ok] * np.log(r[ok]), B)
        r_b[k] = np.where(A_b[k] > 0, np.exp(log_r / np.maximum(A_b[k], 1e-300)), r_b[k])
        for c in range(3):
            E_b[k, :, c] = np.bincount(b, area[ok] * R[ok, c], B)
        seen = np.isfinite(R).all(axis=1) & (True if flag is None else np.asarray(flag(k)) == 0)
        T[k] = area[seen] @ R[seen]
    return A_b, E_b, r_b, T


@functools.cache
def _albedo_grid() -> np.ndarray:
    """log(1 − α) of the albedos searched: the table's own and ``ALBEDO_STEPS`` − 1 between each two."""
    u = _table()[1]
    steps = [np.linspace(u[k], u[k + 1], ALBEDO_STEPS, endpoint=False) for k in range(len(u) - 1)]
    return np.append(np.concatenate(steps), u[-1])


@functools.cache
def _half_space_totals() -> np.ndarray:
    """The half-space's whole diffuse reflectance at each albedo searched (the table's tally)."""
    logc, u, logf, total = _table()
    return np.interp(-_albedo_grid(), -u, total)


def _albedos() -> np.ndarray:
    """The albedos searched."""
    return -np.expm1(_albedo_grid())


def _profile_grid(radii: np.ndarray):
    """The half-space's profile on the searched (α, σ_t) grid at ``radii`` (B,) mm: (albedos, log profile
    (Aα, Gσ, B) mm⁻²)."""
    logc, u, logf, _ = _table()
    uu = _albedo_grid()
    rho = np.log(SIGMA_T_GRID[:, None] * np.asarray(radii)[None])  # (G, B) log mean free paths
    logprof = np.empty((len(uu), len(SIGMA_T_GRID), len(radii)))
    for a, ua in enumerate(uu):
        k = int(np.clip(np.searchsorted(-u, -ua, side="right") - 1, 0, len(u) - 2))
        w = (ua - u[k]) / (u[k + 1] - u[k])
        row = (1 - w) * logf[k] + w * logf[k + 1]
        slope = (row[-1] - row[-2]) / (np.exp(logc[-1]) - np.exp(logc[-2]))
        inside = np.interp(rho, logc, row)
        tail = row[-1] + slope * (np.exp(rho) - np.exp(logc[-1]))
        logprof[a] = np.where(rho <= logc[-1], inside, tail) + 2 * np.log(SIGMA_T_GRID)[:, None]
    return -np.expm1(uu), logprof


def _filled(a_s: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The grid indices (n, 3, 2) with each point and channel that had too few lit rings (−1) given those of
    the nearest point that had enough; one line where no point had."""
    missing = a_s[..., 0] < 0
    if not missing.any():
        return a_s
    for c in range(3):
        have = np.flatnonzero(~missing[:, c])
        if have.size == 0:
            raise TranslucencyError(
                f"data set: no incident point has {MIN_RINGS} lit rings within the fit's reach on its own "
                "side; the medium cannot be estimated (too few photons, or too coarse a mesh)"
            )
        lack = np.flatnonzero(missing[:, c])
        _, near = cKDTree(x[have]).query(x[lack])
        a_s[lack, c] = a_s[have[near], c]
    return a_s


def _match(
    grid, A_b: np.ndarray, E_b: np.ndarray, total: float | None = None
) -> tuple[int, int, float] | None:
    """(albedo index, σ_t index, RMS log residual) of the half-space that best matches one point's rings in
    one channel (``A_b`` the rings' areas mm², ``E_b`` their measured energies Σ A R_d; ``total``: the
    point's whole exitance, matched by the half-space's total reflectance, which holds the albedo); None
    where fewer than ``MIN_RINGS`` rings were lit."""
    albedo, logprof = grid
    ok = (A_b > 0) & (E_b > 0)
    if ok.sum() < MIN_RINGS:
        return None
    m = np.log(E_b[ok] / A_b[ok])
    w = E_b[ok] / E_b[ok].sum()
    P = logprof[..., ok]  # (Aα, G, B)
    shape = ((P - m) ** 2 * w).sum(axis=-1)
    energy = (
        logsumexp(P, axis=-1, b=A_b[ok]) - np.log(E_b[ok].sum())
    ) ** 2  # log Σ_b A_b H(r_b), no underflow
    if total is not None and total > 0:
        energy = energy + (np.log(_half_space_totals()) - np.log(total))[:, None] ** 2
    a, s = np.unravel_index(np.argmin(shape + energy), shape.shape)
    return int(a), int(s), float(np.sqrt(shape[a, s]))
