r"""Fit eq. (1) — or a baseline — to a planar data set, with the modulation texture α.

The data are the windows :math:`y_{ij} \approx R_d(\vec x_i, \vec x_{o,j})` of
a planar data set (:mod:`translucency.io.dataset`).  The model is

.. math:: R_d(\vec x_i, \vec x_o) = \alpha(\vec x_o)\, P_i(\vec x_o),

with α on the sample-wide pixel grid covering all windows and :math:`P_i` the
per-incident-point profile of the chosen family:

``iso``     :math:`(1, s_g, s_b) \sum_k c_k e^{d_k r}` (the paper's isotropic model),
``aniso``   :math:`(1, s_g, s_b) \sum_l w_l(\theta) \sum_k c_{lk} e^{d_{lk} r}` (m directions),
``dipole``  Jensen's dipole with per-point, per-channel :math:`\sigma_a, \sigma_s'`,
``burley``  Christensen–Burley with per-point, per-channel A and s.

(``colour="per-channel"`` gives the exponential families one fall-off per
channel instead of the colour scale.)  r (mm) and θ (rad, in the sample's
frame) of each window pixel come from :func:`translucency.geometry.window_geometry`.

**Objective and alternation** (:mod:`._alternation`, shared with the mesh fit).
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

from .._validate import TranslucencyError
from ..geometry import SampleGrid, window_geometry
from ..io.dataset import PlanarDataset, open_dataset
from ..model import PlanarAlpha
from ._alternation import POOL_POINTS, FitContext, FitResult, alternate, check_fit_options

__all__ = ["FitResult", "PlanarFit", "check_fit_options", "fit_planar"]

#: the result of :func:`fit_planar` (the name before the alternation was shared with meshes)
PlanarFit = FitResult


def fit_planar(
    dataset,
    model: str = "iso",
    *,
    n_terms: int = 3,
    n_directions: int = 8,
    colour: str = "per-channel",
    exclusion_mm: float | None = None,
    weighting: str = "poisson",
    rel_sigma: float = 0.05,
    max_rounds: int = 3,
    tol: float = 1e-3,
    radius_step: float | None | str = "auto",
    sweeps: int = 1,
    balance: bool = True,
    chunk_points: int | None = None,
    workers: int | None = None,
    cache_mb: float = 512,
    checkpoint=None,
    progress: Callable[[int, int, str], None] | None = None,
) -> FitResult:
    """Fit a model family to every incident point of a planar data set, with α.

    Parameters
    ----------
    dataset : PlanarDataset or path
        The measurement (:func:`translucency.io.dataset.open_dataset`).
    model : {"iso", "aniso", "dipole", "burley"}
        Model family (see the module docstring).
    n_terms : int
        n, exponential terms per profile (1–4).
    n_directions : int
        m, directions of the anisotropic model (≥ 2).
    colour : {"shared", "per-channel"}
        Exponential families: the paper's (1, s_g, s_b) scale of one fall-off,
        or one fall-off per channel.
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
        Incident points read and fitted together; default 128, rounded up to
        whole chunks of the store (up to 512) so that no stored chunk is
        decoded twice, and to whole blocks of 16 points (the pooled starts),
        so that the result does not depend on it.
    workers : int, optional
        Chunks fitted in parallel threads (default: the number of CPUs).
    cache_mb : float
        Memory for keeping the decoded data between rounds (float32); chunks
        beyond it are read again from the store each round.
    checkpoint : path, optional
        Save the state after each chunk and resume from it.
    progress : callable, optional
        ``progress(done, total, message)``.

    Returns
    -------
    FitResult

    Examples
    --------
    >>> from translucency.data import default_dataset_path
    >>> fit = fit_planar(default_dataset_path(), "iso", max_rounds=1)   # doctest: +SKIP
    """
    t0 = time.perf_counter()
    check_fit_options(model, n_terms, n_directions, colour, rel_sigma, weighting)
    ds = dataset if isinstance(dataset, PlanarDataset) else open_dataset(dataset)
    if not ds.complete():
        raise TranslucencyError(f"{ds.path}: the acquisition is unfinished; resume it before fitting")
    pitch = ds.pitch
    exclusion = pitch if exclusion_mm is None else float(exclusion_mm)
    if exclusion < 0 or not np.isfinite(exclusion):
        raise TranslucencyError(f"exclusion: must be >= 0 mm, got {exclusion_mm}")
    step = pitch / 4 if radius_step == "auto" else radius_step
    if chunk_points is None:
        stored = int(ds.group["R_d"].chunks[0])
        chunk_points = stored * -(-128 // stored) if stored <= 512 else 128
    elif int(chunk_points) < 1:
        raise TranslucencyError(f"chunk: must be >= 1 point, got {chunk_points}")
    # whole blocks of the pooled cold starts, so that the fit does not depend on the chunking
    chunk_points = POOL_POINTS * -(-int(chunk_points) // POOL_POINTS)
    m = int(n_directions) if model == "aniso" else 1
    n = int(n_terms)
    C = 1 if (colour == "shared" and model in ("iso", "aniso")) else 3
    x_i = ds["x_i"].astype(np.float64)
    origin = ds["window_origin"].astype(np.float64)
    grid = SampleGrid.covering(origin, pitch, ds.window)
    photons = ds.header.get("acquisition", {}).get("photons")
    eta = float(ds.header.get("sample", {}).get("eta", 1.3))
    options = {
        "model": model,
        "n_terms": n,
        "n_directions": m,
        "colour": colour if model in ("iso", "aniso") else "per-channel",
        "exclusion_mm": exclusion,
        "weighting": weighting,
        "rel_sigma": rel_sigma,
        "max_rounds": max_rounds,
        "tol": tol,
        "radius_step": step,
        "sweeps": sweeps,
        "balance": balance,
    }
    request = json.dumps(
        {
            "dataset": str(Path(ds.path).resolve()),
            "header": hashlib.sha256(json.dumps(ds.header, sort_keys=True).encode()).hexdigest(),
            "chunk": chunk_points,
            **options,
        },
        sort_keys=True,
    )

    source = _PlanarSource(ds, grid, origin, photons and 1.0 / (float(photons) * pitch * pitch))
    ctx = FitContext(
        source=source,
        kind=model,
        n=n,
        m=m,
        C=C,
        exclusion=exclusion,
        rel_sigma=rel_sigma,
        weighting=weighting,
        eta=eta,
        radius_step=step,
        sweeps=sweeps,
        balance=balance,
        x_i=x_i,
        cache_left=cache_mb * 2**20,
    )
    return alternate(
        ctx,
        options,
        request,
        max_rounds=max_rounds,
        tol=tol,
        chunk_points=chunk_points,
        workers=workers,
        checkpoint=checkpoint,
        progress=progress,
        t0=t0,
    )


class _PlanarSource:
    """Windows of a planar data set: pixels on the sample grid, α on that grid."""

    def __init__(self, ds: PlanarDataset, grid: SampleGrid, origin: np.ndarray, poisson: float | None):
        self.ds, self.grid, self.origin, self.poisson = ds, grid, origin, poisson or 0.0
        self.alpha_shape = grid.shape
        self.pitch = grid.pitch

    def read(self, ctx: FitContext, s: int, e: int):
        """y (k, J, 3), var or None, valid (k, J), r, θ (1|k, J), pixel (k, J), and the Poisson factor
        of points s..e."""
        ds, k = self.ds, e - s
        ones = np.ones(3, np.float32)  # finite(y @ 1): all three channels finite
        y = ds.read("R_d", s, e).astype(np.float32).reshape(k, -1, 3)
        mask = ds.read("mask", s, e).reshape(k, -1)
        geom = window_geometry(ctx.x_i[s:e], self.origin[s:e], self.grid, ds.window)
        valid = mask & np.isfinite(y @ ones) & (geom.r >= ctx.exclusion)
        var = None
        if not self.poisson > 0:  # with a photon count the weights use the model's Poisson variance
            var = ds.read("variance", s, e).astype(np.float32).reshape(k, -1, 3)
            valid &= np.isfinite(var @ ones)
            var = np.where(valid[..., None], np.maximum(var, 0.0), np.float32(0.0))
        return y, var, valid, geom.r, geom.theta, geom.pixel, self.poisson

    def make_alpha(self, values: np.ndarray):
        return PlanarAlpha(values.copy(), self.grid.origin, self.grid.pitch)
