r"""Per-vertex fit of a 3D object's measurement (the paper's section on real objects).

The data are :math:`R_d(x_i, v)` per incident vertex :math:`x_i` and every
vertex v (:mod:`translucency.acquire.mesh`).  As in the paper, the isotropic
model is fitted with the Euclidean distance :math:`r = |v - x_i|`, and α and
the colour per vertex; the alternation, the weights and the batched solvers are
shared with the planar fit (:mod:`translucency.fit._rounds`), with vertices
in the place of pixels: the Poisson variance of a vertex is :math:`\alpha P/(N A_v)`
for its area :math:`A_v`.

The model keeps what the fit cannot represent but a renderer needs: the mesh's
triangles (so the model renders on its own) and, per incident point, the
measured own-area value and total exitance (:func:`measured_near_field`).
"""

from __future__ import annotations

import hashlib
import json
import time
import warnings

import numpy as np

from .._validate import TranslucencyError
from ..angles import OBLIQUE_DEG
from ..geometry import tangent_frames
from ..io.mesh_dataset import open_mesh_dataset
from ..medium.estimate import estimate_medium
from ..model import VertexAlpha
from ._rounds import alternate
from ._vertex_pool import disc_pool
from .context import FitContext
from .families import FAMILIES
from .held_out import mesh_held_out_terms, vertex_half
from .lean import fit_lean
from .lean_shots import fit_lean_from_shots
from .mesh_pairs import exclusion_radius, mean_edge_length, read_pairs
from .options import FitResult, check_fit_options
from .structure import fit_chosen, resolve_structure
from .through import measure_through

#: α's pooling radius in mean edge lengths.  Measured on the main job's pig against its converged reference
#: (relative RMSE at 96 x 8,000 / 384 x 2,000 / 1,536 x 500 photons): 3 edges 0.082 / 0.070 / 0.078,
#: 6 edges 0.070 / 0.068 / 0.071, 12 edges 0.066 / 0.068 / 0.071 — a narrower disc fits photon noise
#: (α's spread 0.12 / 0.04 / 0.07 at 3 edges), and the error then rose with the number of points
ALPHA_RADIUS_EDGES = 12

#: ... and at least this many mm: the disc must hold as many photons on a scan finer than the pig's (at
#: 338 k vertices, 12 edges are 2.1 mm, and α took the near peak's misfit around each incident point as
#: discs of ±50 %, the picture blotched); the pig's 12 edges at 84-89 k vertices are 4.3 mm
ALPHA_RADIUS_MM = 4.0


def alpha_pool_radius(pitch: float) -> float:
    """α's default pooling radius, mm, for a mesh of mean edge ``pitch`` mm: :data:`ALPHA_RADIUS_EDGES`
    edges, at least :data:`ALPHA_RADIUS_MM`."""
    return max(ALPHA_RADIUS_EDGES * float(pitch), ALPHA_RADIUS_MM)


#: a·D for which a term (Gamma(2) in r: (1 + aD) e^{−aD}) holds 99.9 % of its energy within D
ENERGY_RADIUS_RATE = 9.233


class _MeshSource:
    """Rows of a mesh data set: 'pixels' are vertices, α lives on the vertices."""

    def __init__(self, group, header, alpha_radius: float | None = None, half: int | None = None):
        self.group = group
        self.half = half  # None, or the half of the pairs the fit may use (:func:`.held_out.vertex_half`)
        self.vertices = np.asarray(group["vertices"][...], dtype=np.float64)
        self.area = np.asarray(group["vertex_area"][...], dtype=np.float64)
        self.incident = np.asarray(group["incident"][...])
        self.frame = tangent_frames(np.asarray(group["normals"][...], dtype=np.float64)[self.incident])
        self.alpha_shape = (len(self.vertices),)
        self.stored_points = int(group["R_d"].chunks[0])  # incident points per chunk of the store
        v = self.vertices
        self.pitch = mean_edge_length(v, np.asarray(group["faces"][...]))  # mm
        # α's statistics pooled over a disc of alpha_radius (default ALPHA_RADIUS_EDGES edge lengths): a
        # vertex is lit by few incident points, and α from its own pairs alone is mostly photon noise
        rad = alpha_pool_radius(self.pitch) if alpha_radius is None else float(alpha_radius)
        self._pool = disc_pool(
            v, rad
        )  # (through cells on a scan finer than the disc; built once per surface)
        photons = float(header["photons"])
        self.poisson = (1.0 / (photons * np.maximum(self.area, 1e-12)))[None, :, None].astype(np.float32)

    def read(self, ctx, s: int, e: int):
        y, r, valid = read_pairs(self.group, self.vertices, ctx.x_i, ctx.exclusion, s, e)
        pixel = np.broadcast_to(np.arange(len(self.vertices)), r.shape)
        if self.half is not None:  # held-out evaluation: the other half of the pairs is left out
            valid &= vertex_half(np.arange(s, e), pixel) == self.half
        return y, None, valid, r, np.zeros_like(r), pixel, self.poisson

    def smooth_alpha(self, stat: np.ndarray) -> np.ndarray:
        return self._pool(stat)

    def make_alpha(self, values: np.ndarray):
        return VertexAlpha(values.copy(), self.vertices)


def _held_out(fit: FitResult, ds):
    """Per point, the held-out squared error, data norm and variance of a half fit (structure choice: the
    variance gives its noise floor)."""
    return mesh_held_out_terms(fit, ds.group, variance=True)


def fit_mesh(
    path,
    model: str = "auto",
    *,
    n_terms: int | str | None = None,
    colour: str | None = None,
    exclusion_mm: float | None = None,
    rel_sigma: float = 0.05,
    max_rounds: int = 3,
    tol: float = 1e-3,
    alpha_radius: float | None = None,
    max_rate: float | None = None,
    chunk_points: int = 32,
    workers: int | None = None,
    progress=None,
    scheduler: str | None = "threads",
    half: int | None = None,
) -> FitResult:
    """Fit the isotropic model (or a baseline) per incident vertex of a mesh data set, with α per vertex.

    Parameters
    ----------
    path : path
        A mesh data set (:func:`translucency.acquire.mesh.acquire_mesh`).
    model : {"auto", "iso", "dipole", "burley"}
        The paper fits the isotropic model on objects (no tangent directions); ``"auto"`` (default): the
        isotropic model with n and the colour chosen by held-out error (:mod:`translucency.fit.structure`).
    n_terms : int, "auto" or None
        Exponential terms per profile (1–4); None: chosen with ``model="auto"``, 3 for ``"iso"``.
    colour : {"per-channel", "shared", "auto"}, optional
        None: chosen with ``model="auto"``, a fall-off per channel for ``"iso"``.  The paper's colour
        scale (``"shared"``, one fall-off scaled by (1, s_g, s_b)) gives light that crossed a body the
        hue of the light near its entry: a back-lit marble or potato drawn grey where the reference is
        brown or yellow (the unlit side's blue share 1.21–1.22× the reference's; per channel 1.04 and
        0.82), and the main job's pig's unlit parts too blue (docs/through-body.md, "The unscattered
        light and the colour, measured").
    exclusion_mm : float, optional
        Vertices closer than this to x_i are left out; default half the mean edge length.
    alpha_radius : float, optional
        α at a vertex pools the statistics of the vertices within this distance
        (mm; default ``ALPHA_RADIUS_EDGES`` = 12 mean edge lengths, at least ``ALPHA_RADIUS_MM`` = 4 mm;
        0: per vertex alone).
    max_rate : float, optional
        Steepest fall-off |d| a term may take, mm⁻¹; default 3 / (mean edge length): a term must still
        hold e⁻³ of its value at the nearest vertices, or the data cannot tell its amplitude (a steeper
        term is unconstrained and blows the total 2π Σ c/d² up).  The slowest is 9.23 / (object's size D):
        each term then holds 99.9 % of its energy, (1 + aD) e^{-aD} = 10⁻³, within the object.
    scheduler : str, optional
        Where the chunks run: ``"threads"`` (default), ``"local:N"`` or ``"tcp://HOST:PORT"``
        (:mod:`translucency.cluster`); the result is the same bit for bit.
    half : {0, 1}, optional
        Fit only the pairs (point i, vertex v) with (v + i) mod 2 = ``half`` (held-out evaluation,
        :func:`translucency.fit.held_out.mesh_held_out_terms`); the model then has its profiles and α
        only, not what a renderer needs beside them.  Default: all pairs.

    Returns
    -------
    FitResult
        ``model`` is a mesh model: x_i (N, 3), tangent frames, :class:`VertexAlpha`.

    Examples
    --------
    >>> fit_mesh("object.zarr", "aniso")   # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: model: on meshes the isotropic model is fitted ...
    >>> fit_mesh("object.zarr", "iso", colour="grey")   # options refused before the data set is opened
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: colour: expected 'shared', 'per-channel' or 'auto', got 'grey'
    """
    t0 = time.perf_counter()
    model, n_terms, colour, free, base = _mesh_structure(model, n_terms, colour, rel_sigma, half)
    ds = _open_complete(path)
    if free:  # n and the colour chosen by held-out error on a subset of the points, then fitted on all
        kw = dict(exclusion_mm=exclusion_mm, rel_sigma=rel_sigma, max_rounds=max_rounds, tol=tol,
                  alpha_radius=alpha_radius, max_rate=max_rate, chunk_points=chunk_points, workers=workers,
                  scheduler=scheduler)  # fmt: skip
        return _fit_chosen(ds, free, base, half, progress, kw)
    if half is None:  # a lab's oblique laser shots (import object): one line, not silence
        _warn_oblique(ds)
    source = _MeshSource(ds.group, ds.header, alpha_radius, half)
    exclusion = exclusion_radius(source.pitch, exclusion_mm)
    rate_bounds, a_max = _rate_bounds(source, max_rate)
    settings = dict(rel_sigma=rel_sigma, max_rounds=max_rounds, tol=tol, alpha_radius=alpha_radius)
    options = _mesh_options(model, n_terms, colour, exclusion, source.pitch, a_max, half, **settings)
    ctx = _mesh_context(ds.header, source, rate_bounds, model, n_terms, colour, exclusion, rel_sigma)
    request = _request(ds, options)
    rounds = dict(chunk_points=chunk_points, workers=workers, checkpoint=None, progress=progress, t0=t0)
    result = alternate(ctx, options, request, max_rounds=max_rounds, tol=tol, scheduler=scheduler, **rounds)
    if model == "iso":
        result.options["scaled_to_albedo_bound"] = bound_albedo(result.model).tolist()
    if half is not None:  # a held-out fit: its profiles and α are what is scored
        return result
    _attach_measured(result, ds, exclusion, chunk_points)
    return result


def _mesh_structure(model, n_terms, colour, rel_sigma, half):
    """The model's structure (model, n, colour, the free choices and their base), checked; refused options."""
    if model == "aniso":
        raise TranslucencyError(
            "model: on meshes the isotropic model is fitted (r = |x_o - x_i|, as in the paper)"
        )
    model, n_terms, _, colour, free, base = resolve_structure(model, n_terms, None, colour, planar=False)
    check_fit_options(model, n_terms, 1, colour, rel_sigma)
    if half not in (None, 0, 1):
        raise TranslucencyError(f"half: expected 0 or 1, got {half!r}")
    return model, n_terms, colour, free, base


def _open_complete(path):
    """The mesh data set at ``path``, refused while its acquisition is unfinished."""
    ds = open_mesh_dataset(path)
    if not ds.complete():
        raise TranslucencyError(f"{ds.path}: the acquisition is unfinished; resume it before fitting")
    return ds


def _fit_chosen(ds, free, base, half, progress, kw: dict) -> FitResult:
    """The fit with n and the colour chosen by held-out error (:func:`.structure.fit_chosen`)."""
    if half is not None:
        raise TranslucencyError("half: a held-out fit needs its structure given, not chosen")
    return fit_chosen(fit_mesh, ds, _held_out, free=free, base=base, planar=False, progress=progress, **kw)


def _warn_oblique(ds) -> None:
    """Warn where the data set's photographed beams arrive beyond :data:`OBLIQUE_DEG` off the normal."""
    polar = np.asarray((ds.header.get("photographs") or {}).get("beam_polar_deg", ()), dtype=np.float64)
    oblique = polar[polar > OBLIQUE_DEG]
    if len(oblique):
        warnings.warn(
            f"{ds.path}: {len(oblique)} beam(s) arrive {oblique.min():.0f}–{oblique.max():.0f}° off the "
            "normal (photographs.beam_polar_deg): the profile is fitted to them as if they were normal "
            "beams, and the lean (render --angles) from their asymmetry",
            stacklevel=3,  # fit_mesh's caller (1: this function, 2: fit_mesh)
        )


def _rate_bounds(source, max_rate):
    """ln of the fall-off rates' bounds (ln mm⁻¹) and the steepest rate a_max (mm⁻¹), checked."""
    diagonal = float(np.linalg.norm(np.ptp(source.vertices, axis=0)))
    a_max = 3.0 / source.pitch if max_rate is None else float(max_rate)
    if not (np.isfinite(a_max) and a_max > 0):
        raise TranslucencyError(f"max_rate: must be a positive number of 1/mm, got {max_rate}")
    a_min = ENERGY_RADIUS_RATE / diagonal  # no term spreads its light beyond the object
    if a_min >= a_max:
        raise TranslucencyError(
            f"max_rate: {a_max:.3g} 1/mm is below what the object's size allows ({a_min:.3g})"
        )
    return (float(np.log(a_min)), float(np.log(a_max))), a_max


def _mesh_options(
    model, n_terms, colour, exclusion, pitch, a_max, half, *, rel_sigma, max_rounds, tol, alpha_radius
) -> dict:
    """The options the result records (lengths in mm, the rate in mm⁻¹)."""
    options = {
        "model": model,
        "n_terms": int(n_terms),
        "n_directions": 1,
        "colour": colour,
        "exclusion_mm": exclusion,
        "rel_sigma": rel_sigma,
        "max_rounds": max_rounds,
        "tol": tol,
        "radius_step": pitch / 2,
        "alpha_radius": alpha_radius,
        "max_rate": a_max,
        "geometry": "mesh",
    }
    if half is not None:
        options["half"] = int(half)
    return options


def _request(ds, options: dict) -> str:
    """The request a checkpoint is matched against: the data set's path, its header's hash, the options."""
    header = hashlib.sha256(json.dumps(ds.header, sort_keys=True).encode()).hexdigest()
    return json.dumps({"dataset": str(ds.path.resolve()), "header": header, **options}, sort_keys=True)


def _mesh_context(header, source, rate_bounds, model, n_terms, colour, exclusion, rel_sigma) -> FitContext:
    """The alternation's context: vertices as pixels, one direction, the medium's η and g from the header."""
    return FitContext(
        rate_bounds=rate_bounds,
        source=source,
        family=FAMILIES[model],
        n=int(n_terms),
        m=1,
        C=1 if colour == "shared" and FAMILIES[model].shared_colour else 3,
        exclusion=exclusion,
        rel_sigma=rel_sigma,
        eta=float(header.get("eta", 1.3)),
        g=float(header.get("g", 0.0)),  # the medium's mean cosine where the data set knows it
        radius_step=source.pitch / 2,
        sweeps=1,
        balance=True,
        x_i=source.vertices[source.incident],
        cache_left=512 * 2**20,
    )


def _attach_measured(result: FitResult, ds, exclusion: float, chunk_points: int) -> None:
    """Give the model what the fit does not look at but a renderer needs (module docstring), in place."""
    result.model.faces = np.asarray(ds.group["faces"][...], dtype=np.int64)
    result.model.measured = measured_near_field(ds, chunk_points)
    # the light through the body, measured against the fitted profile (model/through.py): the extension
    if result.model.kind == "exponential":  # the paper's model (the baselines have no c, d to correct)
        result.model.measured["through"] = measure_through(ds, result.model, exclusion=exclusion)
    # the lean (model/lean.py): how the kernel tilts toward the beam's direction, from the oblique beams
    if ds.incidence.count > 1:
        result.model.measured["lean"] = fit_lean(ds, chunk_points)
    elif (from_shots := fit_lean_from_shots(ds)) is not None:  # a lab's oblique shots
        result.model.measured["lean"] = from_shots
    # the medium that reproduces the scan (medium/estimate.py): what a walk of the crossed light reads; a
    # scan too coarse for it (no point with lit rings) keeps the model without one, said in a warning
    try:
        result.model.measured["medium"] = estimate_medium(ds).stacked()
    except TranslucencyError as exc:
        warnings.warn(f"fit: no medium estimated ({exc})", stacklevel=2)
    # the photons per point: how far the physical bounds let a total exceed 1 by noise (model/bounds.py)
    result.model.tally_photons = int(ds.header["photons"]) if ds.header.get("photons") else None
    result.acquisition = ds.header


def bound_albedo(model) -> np.ndarray:
    r"""Scale down, in place, every profile whose plane integral :math:`2\pi \sum_k c_k/d_k^2` exceeds 1
    in some channel; returns the indices of the points scaled.

    On a curved or thin body more surface lies within a distance r of x_i than the plane's
    :math:`\pi r^2` (both sides of a leg, say), so a profile fitted there can integrate to more than the light
    it received over the plane; the bound (energy conservation) is kept by construction, and the renderer
    takes each kernel's total from the measurement anyway (:func:`measured_near_field`).
    """
    total = model.total_reflectance().max(axis=1)  # (N,) over channels
    over = np.flatnonzero(total > 1.0)
    model.c[over] /= total[over, None, None, None]
    return over


def measured_near_field(ds, chunk_points: int = 32) -> dict:
    r"""Per incident point i, what the acquisition measured: ``own`` and ``total``, (P, 3) each.

    .. math:: \mathrm{own}_i = R_d(x_i, x_i), \qquad \mathrm{total}_i = \sum_v A_v\, R_d(x_i, v)

    ``own`` is the tally of the incident vertex's own area (mm⁻²: light that re-emerges within A_i, which
    the fit's exclusion radius leaves out); ``total`` the diffuse exitance per unit incident power.
    """
    area = ds["vertex_area"].astype(np.float64)
    incident = ds["incident"]
    P = len(incident)
    own, total = np.zeros((P, 3)), np.zeros((P, 3))
    for s in range(0, P, chunk_points):
        R = np.asarray(ds.group["R_d"][s : s + chunk_points], dtype=np.float64)  # (k, V, 3)
        own[s : s + len(R)] = R[np.arange(len(R)), incident[s : s + len(R)]]
        total[s : s + len(R)] = np.einsum("kvc,v->kc", R, area)
    return {"own": own, "total": total}
