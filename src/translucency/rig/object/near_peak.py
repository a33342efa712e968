r"""The near peak: R_d of the cells at the laser's hit that no photograph measured (a step of
:mod:`.importer`).

A lab's single exposure clips the spot, and a stated ``spot_radius_mm`` masks it; either way the cells
there (flags :data:`~.fusion.SATURATED`, :data:`~.fusion.SPOT`, and the :data:`~.fusion.UNSEEN` ones
among them) hold a large share of the shot's energy — the steeper the profile, the larger (blue's most).
DISCO kept the peak's local response apart; here it comes from a model of the near peak fitted to the
measured ring around it:

* the **ring**: the measured cells beyond the farthest target cell, out to :data:`RING_MM` further and at
  least :data:`RING_CELLS` of them;
* the **model**, through an index-matched boundary: the half-space's own profile
  :math:`\sigma_t^2 f(\sigma_t r; \alpha)` (:mod:`translucency.model.half_space`) at its calibrated level,
  fitted to the pixels that see the ring and the peak (:class:`.pixel_evidence.PixelEvidence`; the
  clipped ones as lower bounds) or, without them, to the ring's cell means (:func:`_half_space_channel`);
  behind a dielectric the same profile times the gains of walks through that boundary (:mod:`.shape_gain`:
  they hold the light the boundary keeps inside), or, without the scan's walks, Jensen's dipole profile
  :math:`s\,R_d^{dip}(r; \sigma_a, \sigma_s', \eta)` with a free scale s (three parameters a channel,
  fitted to the ring's cell means in log space) — or, where it fits the ring worse or its whole profile
  would return more light than came in (:math:`s\,R^{dip} > 1`: energy is conserved), the exponential
  :math:`a e^{-b r}`;
* the **value**: the model's own cell mean :math:`\int \phi_v\, R\, dA / A_v` over each target cell
  (:func:`.quadrature.cell_quadrature`, graded towards the hit; r the distance from the hit, mm);
* its **variance**: for the half-space, :func:`_half_space_channel`'s; for the dipole, half the difference
  between the two models, squared (the model's form is what is least known), plus the ring's relative
  residual scatter applied to the value.

Units: mm, R_d in mm⁻² per unit incident power.
"""

from __future__ import annotations

import numpy as np

from ...model.dipole import dipole_R_d, dipole_total_reflectance
from ...model.half_space import albedo_range, half_space_R_d
from .pixel_evidence import MODEL_FLOOR, PIXEL_SUB, PixelEvidence
from .quadrature import cell_quadrature

#: the ring reaches this far beyond the farthest target cell, mm (or further, for :data:`RING_CELLS`)
RING_MM = 2.0
#: the fewest measured cells a ring holds
RING_CELLS = 12
#: starting albedos of the half-space's fit, and how close to the best a fit's cost must be to count
STARTS = 6
COST_TOLERANCE = 0.1
#: the ratio between neighbouring σ_t of the scan's table of walks (:mod:`.shape_gain`)
SIGMA_STEP = 2.0


def _half_space_channel(y, r_ring, mean_of, misfit=None, shape=None, quick=False):
    """One channel through an index-matched boundary: the half-space's own profile (σ_t, α) fitted at its
    calibrated level (no free scale: the laser's power is known); the target cells' values and variances,
    whether the profile reads short of the clipped pixels, and the fitted (σ_t, α).

    The fit is to the ring's log cell means ``y`` — or, with ``misfit`` (the residuals of a radial profile
    against the pixels that see the zone, :class:`.pixel_evidence.PixelEvidence`), to the pixels
    themselves: their footprints blur the peak into the ring, and the clipped ones say how bright the core
    at least is.
    The ring holds two numbers well (its level and its slope) and (σ_t, α) can trade one for the other,
    so the fit starts from :data:`STARTS` albedos (σ_t from the ring's slope, σ_tr = σ_t √(3(1 − α))) and
    keeps the best; the variance takes half the spread of the core among the fits as good as the best
    (within :data:`COST_TOLERANCE`), half the difference from the same profile fitted with a free scale
    (what the data say against the calibrated level), and the relative scatter of the data about it
    beyond their noise (the pixels', :meth:`.pixel_evidence.PixelEvidence.relative_scatter`, or the ring's
    cell means') plus :data:`.pixel_evidence.MODEL_FLOOR` (the profile's form), in quadrature."""
    from scipy.optimize import least_squares  # heavy: SciPy's optimisers load where a peak is recovered

    n_ring = len(y)
    lo, hi = albedo_range()
    bounds = ([-8.0, np.log1p(-hi)], [5.0, np.log1p(-lo)])  # log σ_t, u = log(1 − α)
    if shape is not None:  # the scan's gains are known over the table's σ_t and up to its albedo
        set_gain, sigma_ts, albedo_walk, start = shape
        hi = min(hi, albedo_walk)
        bounds = ([np.log(sigma_ts[0]), np.log1p(-hi)], [np.log(sigma_ts[-1]), np.log1p(-lo)])

    def profile(x):  # log σ_t, u, [log s]; the scan's gains at (σ_t, α) set where it has them
        s = np.exp(x[2]) if len(x) > 2 else 1.0
        if shape is not None:
            set_gain(np.exp(x[0]), -np.expm1(x[1]))
        return lambda d: s * half_space_R_d(d, np.exp(x[0]), -np.expm1(x[1]))

    def model(x):
        return mean_of(profile(x))

    def ring_misfit(values):
        return np.log(np.maximum(values[:n_ring], 1e-300)) - y

    def residual(x):
        return misfit(profile(x)) if misfit else ring_misfit(model(x))

    sigma_tr = float(np.clip(-np.polyfit(r_ring, y, 1)[0], 1e-3, 50.0))
    albedos = np.linspace(lo, hi, STARTS + 2)[1:-1] if STARTS > 1 else [0.5 * (lo + hi)]
    if shape is not None or quick:  # fewer starts: each evaluation reweights walks, or a refit follows
        albedos = albedos[[1, -2]]
    starts = [[np.log(sigma_tr / np.sqrt(3 * (1 - albedo))), np.log1p(-albedo)] for albedo in albedos]
    if shape is not None:
        starts.append([np.log(start[0]), np.log1p(-start[1])])
    fits = [least_squares(residual, np.clip(x0, *bounds), bounds=bounds) for x0 in starts]
    costs = np.array([f.cost for f in fits])
    best = fits[int(np.argmin(costs))]
    value = model(best.x)[n_ring:]
    good = [model(f.x)[n_ring:] for f in fits if f.cost <= costs.min() * (1 + COST_TOLERANCE) + 1e-12]
    spread = 0.5 * (np.max(good, axis=0) - np.min(good, axis=0))
    free = best  # (a quick fit, refitted next, states no variance of its own)
    if not quick:
        free = least_squares(residual, [*best.x, 0.0], bounds=([*bounds[0], -5.0], [*bounds[1], 5.0]))
    # the model's relative scatter about the data beyond their noise: the pixels' where fitted to them
    scatter = (
        misfit.relative_scatter(profile(best.x))
        if misfit
        else float(np.sqrt(np.mean(ring_misfit(model(best.x)) ** 2)))  # the ring's cell means'
    )
    variance = (
        spread**2 + (0.5 * (value - model(free.x)[n_ring:])) ** 2 + ((scatter + MODEL_FLOOR) * value) ** 2
    )
    sigma_t, albedo = np.exp(best.x[0]), -np.expm1(best.x[1])
    short = bool(misfit) and misfit.short_of_clip(profile(best.x))  # (the gains left at the best fit's)
    return value, variance, short, (sigma_t, albedo)


def _near_peak_channel(y, r_ring, mean_of, eta, misfit=None, shape=None, quick=False):
    """One channel: the target cells' values, variances, whether the model reads short of the clip and the
    half-space's fitted (σ_t, α) (None for the dipole) — ``mean_of`` gives the cell means of a radial
    profile, ring cells first; through an index-matched boundary the half-space's profile
    (:func:`_half_space_channel`), else the dipole fitted to the ring's log cell means ``y``."""
    from scipy.optimize import least_squares  # heavy: SciPy's optimisers load where a peak is recovered

    if eta == 1.0 or shape is not None:  # the half-space's own profile (the dipole misses its near peak),
        # behind a dielectric times the gains of walks through that boundary (the first pass seeds them)
        return _half_space_channel(y, r_ring, mean_of, misfit, shape, quick)
    n_ring = len(y)

    def dipole(x):  # s R_dip(σ_a, σ_s'): parameters log σ_a, log σ_s', log s
        return np.exp(x[2]) * mean_of(lambda d: dipole_R_d(d, np.exp(x[0]), np.exp(x[1]), eta))

    def exponential(x):  # a e^{-b r}: parameters log a, b
        return np.exp(x[0]) * mean_of(lambda d: np.exp(-x[1] * d))

    def residual(model):
        return lambda x: np.log(np.maximum(model(x)[:n_ring], 1e-300)) - y

    # the first guess from the ring's log slope (a flat or rising ring: the bounds' gentlest profile)
    sigma_tr = float(np.clip(-np.polyfit(r_ring, y, 1)[0], 0.01, 49.0))
    fit = least_squares(
        residual(dipole), [np.log(sigma_tr**2 / 3.0), 0.0, 0.0], bounds=([-12, -6, -20], [6, 6, 20])
    )
    efit = least_squares(
        residual(exponential), [float(np.clip(y.max(), -49, 49)), sigma_tr], bounds=([-50, 0], [50, 50])
    )
    dip, expo = dipole(fit.x)[n_ring:], exponential(efit.x)[n_ring:]
    # the dipole unless it fits the ring worse or its profile would return more light than came in
    albedo = np.exp(fit.x[2]) * float(dipole_total_reflectance(np.exp(fit.x[0]), np.exp(fit.x[1]), eta))
    use_dipole = albedo <= 1.0 and fit.cost <= efit.cost
    value, chosen = (dip, fit) if use_dipole else (expo, efit)
    scatter = float(np.sqrt(np.mean(chosen.fun**2)))  # the ring's relative residual
    return value, (0.5 * (dip - expo)) ** 2 + (scatter * value) ** 2, False, None


def recover_near_peak(mesh, hit, R, var, target, measured, eta: float, views=(), shape=None, scene=None):
    r"""R_d and its variance at the ``target`` cells from the near-peak model fitted to the measured ring.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        mm.
    hit : ndarray, shape (3,)
        Where the laser enters, mm.
    R, var : ndarray, shape (V, 3)
        The fused R_d (mm⁻²) and variance; ``target`` rows are replaced (copies returned).
    target, measured : ndarray of bool, shape (V,)
        The cells to recover; the cells measured (no flag).
    eta : float
        The medium's index (the dipole's boundary term).
    views : sequence
        Per camera (map, E, Var E, usable, clip floor) from :func:`.radiance.shot_cell_means`: the pixels
        the index-matched fit reads (:class:`.pixel_evidence.PixelEvidence`).
    shape : object with ``table(sigma_ts, reach)``, optional
        The scan's own shape (:class:`.shape_gain.MeshWalkGain`): the
        half-space's profile times the walks' per-cell gains, fitted jointly (σ_t and α move the gains
        too; a table of walks over σ_t around the flat fit's, :data:`SIGMA_STEP` apart).
    scene : mitsuba.Scene, optional
        The mesh's scene: the pixels of ``views`` near the hit sampled again, finely
        (:data:`.pixel_evidence.PIXEL_SUB`).

    Returns
    -------
    R, var : ndarray, shape (V, 3)
        With the target cells' model values and variances.
    recovered : bool
        False where no ring of :data:`RING_CELLS` measured cells surrounds the targets (R, var unchanged).
    short : ndarray of bool, shape (3,)
        Per channel, whether the model reads below what the clipped pixels of ``views`` show
        (:meth:`.pixel_evidence.PixelEvidence.short_of_clip`): the peak is steeper than the model can be.
    params : list
        Per channel the half-space's fitted (σ_t mm⁻¹, α), or None (the dipole, or not recovered).

    Examples
    --------
    A field that is a dipole profile comes back at the hit's cell from its ring:

    >>> import trimesh
    >>> from translucency.geometry import vertex_areas
    >>> mesh = trimesh.creation.icosphere(4, radius=20.0)
    >>> hit = np.asarray(mesh.vertices[0])
    >>> truth = lambda y: dipole_R_d(np.linalg.norm(y - hit, axis=1), 0.05, 1.0, 1.3)
    >>> V = len(mesh.vertices)
    >>> pts, w, owner = cell_quadrature(mesh, np.arange(V), toward=hit)
    >>> mean = np.bincount(owner, w * truth(pts), minlength=V) / np.bincount(owner, w, minlength=V)
    >>> R = np.repeat(mean[:, None], 3, axis=1)
    >>> target = np.arange(V) == 0
    >>> out, v, ok, short, _ = recover_near_peak(mesh, hit, R * ~target[:, None], 0 * R, target, ~target, 1.3)
    >>> round(float(out[0, 0] / R[0, 0]), 2)
    1.0
    """
    R, var = R.copy(), var.copy()
    targets = np.flatnonzero(target)
    if not len(targets):
        return R, var, True, np.zeros(3, dtype=bool)
    verts = np.asarray(mesh.vertices, dtype=np.float64)
    r = np.linalg.norm(verts - hit, axis=1)
    ring, r_out = _ring(r, targets, measured, R)
    if ring is None:
        return R, var, False, np.zeros(3, dtype=bool), [None] * 3
    cells = np.concatenate([ring, targets])
    pts, w, owner = cell_quadrature(mesh, cells, toward=hit)
    dist = np.linalg.norm(pts - hit, axis=1)
    gain = np.ones((len(verts), 3))  # the shape's gain per cell (1: the flat half-space's profile)
    straight = np.zeros((len(verts), 3))  # A_v R_v of the light that crosses a sheet unscattered
    ch = 0

    area = np.bincount(owner, weights=w, minlength=len(cells))  # A_v

    def mean_of(profile):  # the cell means (len(cells),) of a radial profile, times each cell's gain
        # (plus the unscattered light where a sheet lets it through: A_v R_v / A_v)
        flat = np.bincount(owner, weights=w * profile(dist), minlength=len(cells)) / area
        return flat * gain[cells, ch] + straight[cells, ch] / area

    sample = _pixel_sampler(scene, mesh)
    pixels = PixelEvidence(views, hit, r_out, mesh if shape is not None else None, sample) if views else None
    short = np.zeros(3, dtype=bool)
    params = [None, None, None]
    # the flat fit first; then, with the scan's shape, the profile times the walks' gains fitted jointly
    # (a table of walks over σ_t around the flat fit's, reweighted for the albedo)
    walks = shape is not None
    if pixels:
        pixels.gain = gain  # (the same array: the gains set below are the pixels' too)
    for walk in range(1 + walks):
        table = shape.table(_sigma_grid(params), reach=r_out + 1.0) if walk else None
        refit = walks and not walk  # the flat fit only starts the joint one
        for ch in range(3):
            if pixels:
                pixels.channel = ch
            shape_ch = None
            if table is not None:

                def set_gain(sigma_t, albedo, ch=ch, table=table):  # channel ch's near gains at (σ_t, α)
                    gain[table.cells.near, ch] = table(sigma_t, albedo)
                    straight[:, ch], point = table.ballistic(sigma_t)
                    if pixels:
                        pixels.delta(ch, point, float(straight[:, ch].sum()))

                shape_ch = (set_gain, table.sigma_ts, table.albedo_walk, params[ch])
            value, variance, short[ch], params[ch] = _near_peak_channel(
                np.log(R[ring, ch]), r[ring], mean_of, 1.0 if walks else eta, pixels or None, shape_ch, refit
            )
            R[targets, ch], var[targets, ch] = value, variance
    return R, var, True, short, params


def _ring(r: np.ndarray, targets: np.ndarray, measured: np.ndarray, R: np.ndarray):
    """The ring's cells (measured, R_d > 0, beyond the targets) and its outer radius r_out (mm), nearest
    first: at least :data:`RING_CELLS` of them and :data:`RING_MM` wide; (None, None) with too few."""
    r_in = r[targets].max()
    outside = np.flatnonzero(measured & (r > r_in) & np.all(R > 0, axis=1))
    if len(outside) < RING_CELLS:
        return None, None
    order = outside[np.argsort(r[outside])]
    r_out = max(r_in + RING_MM, r[order[RING_CELLS - 1]])
    return order[r[order] <= r_out], r_out


def _pixel_sampler(scene, mesh):
    """The rays of a camera's pixels near the hit, PIXEL_SUB² each, through ``scene`` (None: none)."""
    if scene is None:
        return None

    def sample(m, pixels):  # the rays of a camera's pixels, PIXEL_SUB² each
        return m.sample_pixels(pixels, PIXEL_SUB, scene, mesh)

    return sample


def _sigma_grid(params) -> np.ndarray:
    """σ_t (mm⁻¹) of the walks a shape's table takes: from a fifth of the flat fits' least to twice
    their largest (a thin part's flat fit reads σ_t up to 4× high), :data:`SIGMA_STEP` apart in ratio;
    within 0.02-30 mm⁻¹ and at least one step wide (a noisy flat fit can read σ_t below the floor).

    Examples
    --------
    >>> g = _sigma_grid([(1.0, 0.9), (4.0, 0.8), None])
    >>> float(g[0]), float(g[-1]), bool((g[1:] / g[:-1] <= SIGMA_STEP * (1 + 1e-12)).all())
    (0.2, 8.0, True)
    >>> _sigma_grid([(0.005, 0.9)])  # below the floor: the floor and one step
    array([0.02, 0.04])
    """
    sigma_t = [p[0] for p in params if p is not None]
    lo = max(min(sigma_t) / 5.0, 0.02)
    hi = max(min(2.0 * max(sigma_t), 30.0), lo * SIGMA_STEP)
    n = max(2, int(np.ceil(np.log(hi / lo) / np.log(SIGMA_STEP))) + 1)
    return np.geomspace(lo, hi, n)


__all__ = ["recover_near_peak", "RING_MM", "RING_CELLS"]
