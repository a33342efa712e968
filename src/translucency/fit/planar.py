r"""Fit eq. (1) — or a baseline — to a planar data set, with the modulation texture α.

The data are the windows :math:`y_{ij} \approx R_d(\vec x_i, \vec x_{o,j})` of
a planar data set (:mod:`translucency.io.dataset`).  The model is

.. math:: R_d(\vec x_i, \vec x_o) = \alpha(\vec x_o)\, P_i(\vec x_o),

with α on the sample-wide pixel grid covering all windows and :math:`P_i` the
per-incident-point profile of the chosen family:

``iso``     :math:`(1, s_g, s_b) \sum_k c_k e^{d_k r}` (the paper's isotropic model),
``aniso``   :math:`(1, s_g, s_b) \sum_l w_l(\theta) \sum_k c_{lk} e^{d_{lk} r}` (m directions),
``dipole``  Jensen's dipole with per-point, per-channel :math:`\sigma_a, \sigma_s'`,
``burley``  Christensen–Burley with per-point, per-channel A and s,
``pbd``     photon beam diffusion (Habel et al. 2013) with per-point, per-channel σ_a, σ_s',
``ddipole`` the directional dipole (Frisvad et al. 2014) at normal incidence, likewise.

(``colour="per-channel"`` gives the exponential families one fall-off per
channel instead of the colour scale.)  r (mm) and θ (rad, in the sample's
frame) of each window pixel come from :func:`translucency.geometry.window_geometry`.

**Objective and alternation** (:mod:`.chunk`, :mod:`._rounds`, shared with the mesh fit).
Weighted least squares over every valid pair,

.. math:: \Phi = \sum_{i,j,\lambda} w_{ij\lambda}^2
          \bigl(\alpha_j P_{i\lambda}(\vec x_j) - y_{ij\lambda}\bigr)^2, \qquad
          w^{-2} = \bigl[(\rho\, m)^2 + m/(N p^2)\bigr] / \min(1, 1\,\mathrm{mm}/r),

with m = αP of round 1's fitted model (round 1 itself: ring means of the data),
N the data set's photon count and ρ = 0 (``weighting="poisson"``, default) or
``rel_sigma`` (``"relative"``).  Minimised by alternating between every point's
parameters (α fixed) and α in closed form, :math:`\alpha_j = \sum w^2 P y /
\sum w^2 P^2`, normalised to mean 1; every round is scored under the same
weights, the rounds stop when Φ falls by less than ``tol`` or rises, and the
best round is returned.  Masked, non-finite and excluded pixels (r below
``exclusion_mm``, one pixel by default) have weight 0.

**Pooled α** (``alpha_radius`` > 0): α_j pools the sums of every pixel within
that distance, :math:`\alpha_j = \sum_{|j'-j| \le \rho} \sum w^2 P y / \sum_{|j'-j| \le \rho} \sum w^2 P^2`
(as the mesh fit's α over a disc of vertices).  Per pixel (the default) α is free
at every pixel; where few windows overlap a pixel — a sparse grid of incident
points, or noisy data such as rendered or real photographs — it then follows the
noise of those few values (docs/validation/planar-rig.md), and the pooled α keeps only
the modulation on scales beyond ρ.

Work runs in chunks of incident points read from the Zarr store, so a data
set larger than memory can be fitted; with ``checkpoint`` the state is saved
after every chunk and an interrupted fit resumes from it.
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy.ndimage import correlate

from .._validate import TranslucencyError
from ..geometry import SampleGrid, window_geometry
from ..io.dataset import PlanarDataset, open_dataset
from ..model import PlanarAlpha, Rectangle
from ._rounds import alternate
from .chunk import POOL_POINTS
from .context import FitContext
from .families import FAMILIES
from .held_out import held_out_terms, pair_half
from .options import FitResult, check_fit_options
from .structure import fit_chosen, resolve_structure

__all__ = [
    "FitResult",
    "PlanarFit",
    "check_fit_options",
    "fit_planar",
]

#: a structure's held-out error counts pairs from this distance (mm) on: the two interleaved halves have
#: different exact radii near x_i, and a per-direction fit from half the pixels extrapolates between them
#: (scored over all radii, near-field spikes hide a fibrous material's anisotropy; docs/fitting.md)
NEAR_MM = 1.0


def _held_out(fit: FitResult, ds: PlanarDataset):
    """Per point, the held-out squared error, data norm and variance beyond :data:`NEAR_MM` (structure
    choice: the variance gives its noise floor)."""
    return held_out_terms(fit, ds, near=NEAR_MM, variance=True)


#: the result of :func:`fit_planar` (the name before the alternation was shared with meshes)
PlanarFit = FitResult


#: how far above a tally's measured total (all exits) a fitted model's total may lie before the
#: profile is refitted with narrower rates (the fit's own error in the total is ~10 % RMS, docs/accuracy.md)
TOTAL_TOLERANCE = 0.2


def default_chunk_points(n_points: int, stored: int) -> int:
    """Incident points per chunk when none is asked for: an eighth of the data set, at least 128 and at
    most 512, rounded up to whole chunks of the store (of ``stored`` points; up to 512) so that no
    stored chunk is decoded twice.

    A chunk is the unit of work sent to a thread or a worker; its points are computed
    :data:`~translucency.fit.FIT_BLOCK` at a time, so a larger chunk costs memory only
    for its data.  Large data sets get 512-point chunks: a task then runs for ~0.2 s, and the
    scheduler's few ms per task stay below 5 % of the fit (benchmarks/scale_out.py).  The choice
    depends only on the data set, so every scheduler gets the same chunks and the same result.

    Examples
    --------
    >>> default_chunk_points(1024, 64), default_chunk_points(4096, 64), default_chunk_points(100_000, 1000)
    (128, 512, 512)
    """
    want = int(np.clip(-(-n_points // 8), 128, 512))
    return stored * -(-want // stored) if stored <= 512 else want


def fit_planar(dataset, model: str = "auto", *, n_terms: int | str | None = None,
    n_directions: int | str | None = None, colour: str | None = None, exclusion_mm: float | None = None,
    weighting: str = "poisson", rel_sigma: float = 0.05, max_rounds: int = 3, tol: float = 1e-3,
    radius_step: float | None | str = "auto", sweeps: int = 1, balance: bool = True,
    chunk_points: int | None = None, workers: int | None = None, cache_mb: float = 512, checkpoint=None,
    half: int | None = None, progress: Callable[[int, int, str], None] | None = None,
    scheduler: str | None = "threads", alpha_radius: float | None = None,
) -> FitResult:  # fmt: skip
    """Fit a model family to every incident point of a planar data set, with α.

    Parameters
    ----------
    dataset : PlanarDataset or path
        The measurement (:func:`translucency.io.dataset.open_dataset`).
    model : {"auto", "iso", "aniso", "dipole", "burley", "pbd", "ddipole"}
        Model family (see the module docstring); ``"auto"`` (default): the sum of exponentials with its
        structure (colour, n, m) chosen by held-out error (:mod:`translucency.fit.structure`).
    n_terms : int, "auto" or None
        n, exponential terms per profile (1–4); ``"auto"``: chosen from 1–4 by held-out error.  None:
        chosen with ``model="auto"``, 3 for a named family.
    n_directions : int, "auto" or None
        m, directions of the anisotropic model (≥ 2); ``"auto"``: chosen from {1, 2, 4, 8, 16} by
        held-out error (m = 1: the isotropic model).  None: chosen with ``model="auto"``, 8 for "aniso".
    colour : {"shared", "per-channel", "auto"}, optional
        Exponential families: the paper's (1, s_g, s_b) scale of one fall-off, or one fall-off per
        channel.  None: chosen with ``model="auto"``, per channel for a named family.
    exclusion_mm : float, optional
        Pixels closer than this to x_i are ignored; default one pixel.
    weighting : {"poisson", "relative"}
        w⁻² = αP/(N p²), the Poisson variance of a model (default: its shape does
        not depend on N, so more photons never hurt), or (ρ αP)² + αP/(N p²),
        a relative error ρ where the data are precise (see docs/fitting.md).
    rel_sigma : float
        ρ, the relative tolerance of the "relative" weighting.
    max_rounds, tol : int, float
        At most ``max_rounds`` rounds; they stop when Φ (under the common weights of
        rounds ≥ 2) falls by less than ``tol`` relatively, or rises.  The best round is returned.
    radius_step : float, None or "auto"
        Merge radii beyond 1 mm into rings of this width (mm); ``None`` groups
        exactly equal radii only; ``"auto"`` is a quarter pixel.
    sweeps : int
        Block-coordinate sweeps over the directions per round (aniso).
    chunk_points : int, optional
        Incident points read and fitted together (a task); default
        :func:`default_chunk_points` (an eighth of the points, 128 to 512, in
        whole stored chunks); rounded up to whole blocks of 16 points (the
        pooled starts), so that the result does not depend on it.
    workers : int, optional
        Chunks fitted in parallel threads (default: the number of CPUs).
    cache_mb : float
        Memory for keeping the decoded data between rounds (float32); chunks
        beyond it are read again from the store each round.
    checkpoint : path, optional
        Save the state after each chunk and resume from it.
    half : {0, 1}, optional
        Fit only the pairs (point i, sample-grid pixel (row, col)) with
        (row + col + i) mod 2 = ``half``: two interleaved halves of every window,
        alternating between points, so that α at a pixel held out in one window is
        fitted from the others (held-out evaluation, :func:`held_out_error`).  Default: all pairs.
    progress : callable, optional
        ``progress(done, total, message)``.
    scheduler : str, optional
        Where the chunks run: ``"threads"`` (default), ``"local:N"`` or ``"tcp://HOST:PORT"``
        (:mod:`translucency.cluster`; the data set's path must be visible to the workers).  The
        result is the same bit for bit; ``cache_mb`` is then per worker.
    alpha_radius : float, optional
        α at a pixel pools the statistics of the pixels within this distance (mm) of it
        (module docstring); default ``None`` or 0: α per pixel.  For data where few windows
        overlap each pixel or the data are noisy (photographs), where a radius of a few mm lowers the
        held-out error (docs/fitting.md, docs/validation/planar-rig.md).

    Returns
    -------
    FitResult

    Examples
    --------
    >>> from translucency.data import default_dataset_path
    >>> from translucency.fit import fit_planar
    >>> fit = fit_planar(default_dataset_path(), "iso", n_terms=2, max_rounds=1)
    >>> fit.model.n_points, fit.model.n_terms, len(fit.history)
    (1024, 2, 1)
    """
    t0 = time.perf_counter()
    structure = _planar_structure(model, n_terms, n_directions, colour, rel_sigma, weighting)
    model, n_terms, n_directions, colour, free, base = structure
    ds, pool = _open_checked(dataset, alpha_radius)
    kw = dict(exclusion_mm=exclusion_mm, weighting=weighting, rel_sigma=rel_sigma, max_rounds=max_rounds,
              tol=tol, radius_step=radius_step, sweeps=sweeps, balance=balance, chunk_points=chunk_points,
              workers=workers, cache_mb=cache_mb, checkpoint=checkpoint, scheduler=scheduler,
              alpha_radius=alpha_radius)  # fmt: skip
    if free:  # the structure chosen by held-out error on a subset of the points, then fitted on all
        return _fit_chosen(ds, free, base, half, progress, kw)
    exclusion, step, chunk_points = _radii_and_chunk(ds, exclusion_mm, radius_step, chunk_points)
    options = _planar_options(structure, exclusion, step, pool, kw)
    request = _request(ds, options, chunk_points, half)
    source = _planar_source(ds, half, pool)
    ctx = _planar_context(source, options, cache_mb)
    rounds = dict(chunk_points=chunk_points, workers=workers, checkpoint=checkpoint, progress=progress, t0=t0)
    result = alternate(ctx, options, request, max_rounds=max_rounds, tol=tol, scheduler=scheduler, **rounds)
    _bound_model(result, source, ds, model)
    return result


def _planar_structure(model, n_terms, n_directions, colour, rel_sigma, weighting):
    """The structure (model, n, m, colour, the free choices and their base), resolved and checked."""
    structure = resolve_structure(model, n_terms, n_directions, colour, planar=True)
    model, n_terms, n_directions, colour, _, _ = structure
    check_fit_options(model, n_terms, n_directions, colour, rel_sigma, weighting)
    return structure


def _open_checked(dataset, alpha_radius):
    """The data set, refused while its acquisition is unfinished, and α's pooling radius (mm, 0: none)."""
    ds = dataset if isinstance(dataset, PlanarDataset) else open_dataset(dataset)
    if not ds.complete():
        raise TranslucencyError(f"{ds.path}: the acquisition is unfinished; resume it before fitting")
    pool = 0.0 if alpha_radius is None else float(alpha_radius)
    if not (pool >= 0 and np.isfinite(pool)):
        raise TranslucencyError(f"alpha_radius: must be >= 0 mm, got {alpha_radius}")
    return ds, pool


def _fit_chosen(ds, free, base, half, progress, kw: dict) -> FitResult:
    """The fit with its structure chosen by held-out error (:func:`.structure.fit_chosen`)."""
    if half is not None:
        raise TranslucencyError("half: a held-out fit needs its structure given, not chosen")
    return fit_chosen(fit_planar, ds, _held_out, free=free, base=base, planar=True, progress=progress, **kw)


def _radii_and_chunk(ds, exclusion_mm, radius_step, chunk_points):
    """The exclusion radius and the ring width (mm), and the points per chunk, checked."""
    pitch = ds.pitch
    exclusion = pitch if exclusion_mm is None else float(exclusion_mm)
    if exclusion < 0 or not np.isfinite(exclusion):
        raise TranslucencyError(f"exclusion: must be >= 0 mm, got {exclusion_mm}")
    step = pitch / 4 if radius_step == "auto" else radius_step
    if chunk_points is None:  # an eighth of the points, 128 to 512, in whole stored chunks (below)
        chunk_points = default_chunk_points(ds.n_points, int(ds.group["R_d"].chunks[0]))
    elif int(chunk_points) < 1:
        raise TranslucencyError(f"chunk: must be >= 1 point, got {chunk_points}")
    # whole blocks of the pooled cold starts, so that the fit does not depend on the chunking
    chunk_points = POOL_POINTS * -(-int(chunk_points) // POOL_POINTS)
    return exclusion, step, chunk_points


def _planar_options(structure, exclusion: float, step, pool: float, kw: dict) -> dict:
    """The options the result records (lengths in mm), from the structure and the keyword settings."""
    model, n_terms, n_directions, colour, _, _ = structure
    shared = FAMILIES[model].shared_colour  # the exponential families have the colour scale
    options = {
        "model": model,
        "n_terms": int(n_terms),
        "n_directions": int(n_directions) if FAMILIES[model].directional else 1,
        "colour": colour if shared else "per-channel",
        "exclusion_mm": exclusion,
        "weighting": kw["weighting"],
        "rel_sigma": kw["rel_sigma"],
        "max_rounds": kw["max_rounds"],
        "tol": kw["tol"],
        "radius_step": step,
        "sweeps": kw["sweeps"],
        "balance": kw["balance"],
    }
    if pool > 0:  # recorded only when set: per-pixel fits keep their options (and checkpoints) as before
        options["alpha_radius"] = pool
    return options


def _request(ds, options: dict, chunk_points: int, half) -> str:
    """The request a checkpoint is matched against (data set, header hash, chunk, options); records ``half``
    in ``options``, checked."""
    request = json.dumps(
        {
            "dataset": str(Path(ds.path).resolve()),
            "header": hashlib.sha256(json.dumps(ds.header, sort_keys=True).encode()).hexdigest(),
            "chunk": chunk_points,
            **options,
        },
        sort_keys=True,
    )
    if half is not None:
        if half not in (0, 1):
            raise TranslucencyError(f"half: expected 0 or 1, got {half!r}")
        options["half"] = int(half)
        request = json.dumps({**json.loads(request), "half": int(half)}, sort_keys=True)
    return request


def _planar_source(ds, half, pool: float) -> _PlanarSource:
    """The windows on the grid covering them, with the Poisson factor 1/(N p²) (mm⁻²) where N is known."""
    origin = ds["window_origin"].astype(np.float64)
    grid = SampleGrid.covering(origin, ds.pitch, ds.window)
    photons = ds.header.get("acquisition", {}).get("photons")
    poisson = photons and 1.0 / (float(photons) * ds.pitch * ds.pitch)
    return _PlanarSource(ds, grid, origin, poisson, half, pool)


def _planar_context(source: _PlanarSource, options: dict, cache_mb: float) -> FitContext:
    """The alternation's context, from the recorded options and the sample's η and g (header)."""
    sample = source.ds.header.get("sample", {})
    return FitContext(
        source=source,
        family=FAMILIES[options["model"]],
        n=options["n_terms"],
        m=options["n_directions"],
        C=1 if options["colour"] == "shared" else 3,  # the colour scale of the exponential families
        exclusion=options["exclusion_mm"],
        rel_sigma=options["rel_sigma"],
        weighting=options["weighting"],
        eta=float(sample.get("eta", 1.3)),
        g=float(sample.get("g", 0.0)),  # the medium's mean cosine, 0 where unknown
        radius_step=options["radius_step"],
        sweeps=options["sweeps"],
        balance=options["balance"],
        x_i=source.ds["x_i"].astype(np.float64),
        cache_left=cache_mb * 2**20,
    )


def _bound_model(result: FitResult, source: _PlanarSource, ds, model: str) -> None:
    """The energy guard's bound on the model returned (after α's last normalisation), and what the physical
    bounds need (model/bounds.py): the sample the windows lie on, the tally's photons; in place."""
    bound = np.where(source.noisy_points()[:, None], source.total_bound(0, ds.n_points), np.inf)
    scaled = FAMILIES[model].keep_totals(result.model, bound)  # noise-free profiles keep their own tails
    if scaled.size:
        result.options["scaled_to_total_bound"] = scaled.tolist()
    result.model.extent = sample_extent(ds)
    photons = ds.header.get("acquisition", {}).get("photons")
    result.model.tally_photons = int(photons) if photons and source.tally_total else None


def sample_extent(ds: PlanarDataset) -> Rectangle | None:
    """The top face of the sample a planar data set was acquired on: [0, W] × [0, H] mm from its header's
    ``sample.size_mm`` (an acquisition's slab); None where the header does not say (imported data: the
    bounds take α's support)."""
    size = (ds.header.get("sample") or {}).get("size_mm")
    if not size or len(size) < 2 or not all(np.isfinite(float(v)) and float(v) > 0 for v in size[:2]):
        return None
    return Rectangle((0.0, 0.0), (float(size[0]), float(size[1])))


class _PlanarSource:
    """Windows of a planar data set: pixels on the sample grid, α on that grid."""

    def __init__(
        self,
        ds: PlanarDataset,
        grid: SampleGrid,
        origin: np.ndarray,
        poisson: float | None,
        half=None,
        alpha_radius: float = 0.0,
    ):
        self.ds, self.grid, self.origin, self.poisson = ds, grid, origin, poisson or 0.0
        self.half = half  # None, or the half of the pairs the fit may use (:func:`pair_half`)
        self.alpha_shape = grid.shape
        self.pitch = grid.pitch
        self.stored_points = int(ds.group["R_d"].chunks[0])  # incident points per chunk of the store
        # α's statistics pooled over a disc (module docstring); None: α per pixel (the alternation's
        # update_alpha calls smooth_alpha only where a source has one)
        self.smooth_alpha = DiscPool(alpha_radius / grid.pitch) if alpha_radius > 0 else None
        # a photon tally counts every exit, inside the window or not: its total bounds the model's
        est = str((ds.header.get("acquisition") or {}).get("estimator") or "")
        self.tally_total = est.startswith("analog photon tally")

    def total_bound(self, s: int, e: int) -> np.ndarray:
        """(k, 3) the most total diffuse reflectance a model of points s..e may have: 1 (energy
        conservation), and :data:`TOTAL_TOLERANCE` above the measured total where the data set's
        ``total_diffuse`` counts every exit (a photon tally; a camera sees only its windows)."""
        bound = np.ones((e - s, 3))
        if self.tally_total:
            measured = self.ds.read("total_diffuse", s, e).astype(np.float64)
            ok = np.isfinite(measured) & (measured > 0)
            bound = np.where(ok, np.minimum(bound, (1 + TOTAL_TOLERANCE) * measured), bound)
        return bound

    def noisy_points(self) -> np.ndarray:
        """(P,) bool: the point's window has noise — a photon count, or a variance somewhere (the windows
        the energy guard bounds; noise-free ones, a simulation's exact profiles, determine their tails)."""
        if self.poisson > 0:
            return np.ones(self.ds.n_points, dtype=bool)
        out = np.zeros(self.ds.n_points, dtype=bool)
        for s in range(0, self.ds.n_points, self.stored_points):
            e = min(s + self.stored_points, self.ds.n_points)
            var = self.ds.read("variance", s, e).astype(np.float64).reshape(e - s, -1)
            out[s:e] = np.nansum(np.maximum(var, 0.0), axis=1) > 0
        return out

    def read(self, ctx: FitContext, s: int, e: int):
        """y (k, J, 3), var or None, valid (k, J), r, θ (1|k, J), pixel (k, J), and the Poisson factor
        of points s..e."""
        ds, k = self.ds, e - s
        ones = np.ones(3, np.float32)  # finite(y @ 1): all three channels finite
        y = ds.read("R_d", s, e).astype(np.float32).reshape(k, -1, 3)
        mask = ds.read("mask", s, e).reshape(k, -1)
        geom = window_geometry(ctx.x_i[s:e], self.origin[s:e], self.grid, ds.window)
        valid = mask & np.isfinite(y @ ones) & (geom.r >= ctx.exclusion)
        if self.half is not None:  # held-out evaluation: the other half of the pairs is left out
            valid &= (
                pair_half(np.arange(s, e), np.broadcast_to(geom.pixel, valid.shape), self.grid) == self.half
            )
        var = None
        if not self.poisson > 0:  # with a photon count the weights use the model's Poisson variance
            var = ds.read("variance", s, e).astype(np.float32).reshape(k, -1, 3)
            valid &= np.isfinite(var @ ones)
            var = np.where(valid[..., None], np.maximum(var, 0.0), np.float32(0.0))
        return y, var, valid, geom.r, geom.theta, geom.pixel, self.poisson

    def make_alpha(self, values: np.ndarray):
        return PlanarAlpha(values.copy(), self.grid.origin, self.grid.pitch)


class DiscPool:
    """Sums of a statistic on the sample grid over a disc of ``radius_px`` pixels (centre to centre) around
    every pixel: α's pooling (``alpha_radius``); pixels outside the grid count 0.

    Examples
    --------
    >>> stat = np.zeros((5, 5)); stat[2, 2] = 1.0
    >>> DiscPool(1.0)(stat).astype(int).tolist()[1:4]
    [[0, 0, 1, 0, 0], [0, 1, 1, 1, 0], [0, 0, 1, 0, 0]]
    """

    def __init__(self, radius_px: float):
        k = int(np.floor(radius_px + 1e-9))
        dy, dx = np.mgrid[-k : k + 1, -k : k + 1]
        self.kernel = (dx * dx + dy * dy <= radius_px * radius_px + 1e-9).astype(np.float64)

    def __call__(self, stat: np.ndarray) -> np.ndarray:
        return correlate(np.asarray(stat, dtype=np.float64), self.kernel, mode="constant", cval=0.0)
