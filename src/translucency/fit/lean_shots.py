r"""The lean (:mod:`translucency.model.lean`) from a lab's shots: one beam a point, at the angle it came.

``acquire mesh --incidence`` lights every point with the normal beam and oblique ones, and
:func:`translucency.fit.lean.fit_lean` reads the lean from the oblique beam *against the normal one*.  A
lab's laser meets each point once, from wherever the rig put it (a fixed laser and a turntable light most
points obliquely), so there is no normal beam to compare with.  But the lean is odd about the beam's
plane and the profile is not: within a band of distance from the hit, the lean's factor
:math:`e^{\kappa\,\vec\ell\cdot\hat d}` averages out over the directions, so the band's mean is the
normal beam's profile up to one factor per band — which the fit's normalisation :math:`Z` and reach
term take up.  So the shot's **symmetric part**

.. math:: \bar R(v) = \frac{\sum_{u \in b(v)} A_u R(u)}{\sum_{u \in b(v)} A_u},
          \qquad b(v) = \{u : \lfloor r_u / \Delta \rfloor = \lfloor r_v / \Delta \rfloor\},

(Δ = :data:`BAND_MM`, r the distance from the hit) stands in for the normal beam, and the oblique shot
itself for the oblique beam, in :func:`translucency.fit.lean.fit_point`'s three steps.  The band's mean
keeps a little of the lobe (:math:`\langle e^{\kappa a}\rangle > 1` and grows with r), so the
symmetric part is taken again of the shot with the lean found so far divided out,
:math:`\overline{R\,e^{-\kappa\,\vec\ell\cdot\hat d}}`, and the fit repeated (:data:`ROUNDS`): on a
marble ball the single shot's κ is then 0.94–1.02 of the paired beams' (0.79–0.91 after one round).
Shots within :data:`translucency.angles.OBLIQUE_DEG` of the normal carry no lean of their own (ℓ ≈ 0):
their points take the median of the oblique shots' (κ, λ), the material's.

What this cannot tell from a lean: an asymmetry the object's shape makes about the hit (a ridge, an
edge), which a normal beam would show too — on a ball there is none (``tests/test_lean.py``).
Units: κ dimensionless, λ mm⁻¹, distances mm.
"""

from __future__ import annotations

import numpy as np

from ..angles import OBLIQUE_DEG, polar_deg
from ..model.lean import lean_vector
from .lean import fit_point

#: the width of the bands of distance (mm) over which a shot's symmetric part is taken
BAND_MM = 0.5
#: rounds of (symmetric part of the shot with the lean so far taken out, fit): the first alone keeps part
#: of the lobe in the band's mean and reads κ ~13 % low on a ball; a second and third take it out
ROUNDS = 3


def symmetric_part(R: np.ndarray, area: np.ndarray, r: np.ndarray, band_mm: float = BAND_MM) -> np.ndarray:
    """The area-weighted mean of ``R`` (V, C) over each vertex's band of distance ``r`` (V,) from the hit.

    Examples
    --------
    >>> R = np.array([[4.0], [1.0], [3.0], [2.0]])
    >>> symmetric_part(R, np.ones(4), np.array([0.0, 0.6, 0.7, 1.2]))[:, 0].tolist()
    [4.0, 2.0, 2.0, 2.0]
    """
    band = np.floor(r / band_mm).astype(np.int64)
    n = int(band.max()) + 1
    weight = np.bincount(band, area, minlength=n)
    out = np.empty_like(R, dtype=np.float64)
    for c in range(R.shape[1]):
        out[:, c] = np.bincount(band, area * R[:, c], minlength=n)[band] / np.maximum(weight[band], 1e-300)
    return out


def lean_of_shot(R, area, vertices, hit_vertex: int, normal, toward, eta: float = 1.0) -> np.ndarray:
    """(κ, λ) per channel, (2, C), of one shot: ``R`` (V, C) its R_d, lit from unit ``toward`` (toward the
    laser) at vertex ``hit_vertex`` of unit ``normal``; the relative index ``eta`` refracts the beam.

    Examples
    --------
    A response leaning along +x by e^{κ ℓ · d̂} on a flat disc of vertices is read back:

    >>> rng = np.random.default_rng(0)
    >>> xy = rng.uniform(-4, 4, (4000, 2))
    >>> V = np.column_stack([xy, np.zeros(4000)])
    >>> V[0] = 0.0
    >>> n, toward = np.array([0.0, 0, 1]), np.array([-np.sin(1.0), 0.0, np.cos(1.0)])
    >>> ell = lean_vector(toward[None], n[None], 1.0)[0]
    >>> r = np.linalg.norm(V, axis=1)
    >>> d_hat = np.divide(V, r[:, None], out=np.zeros_like(V), where=r[:, None] > 0)
    >>> R = (np.exp(-r) * np.exp(1.5 * d_hat @ ell))[:, None]
    >>> kappa, lam = lean_of_shot(R, np.ones(4000), V, 0, n, toward)
    >>> bool(abs(kappa[0] - 1.5) < 0.15)
    True
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    d = vertices - vertices[hit_vertex]
    r = np.linalg.norm(d, axis=1)
    use = r > 0  # the hit's own vertex has no direction
    d_hat = np.divide(d, r[:, None], out=np.zeros_like(d), where=use[:, None])
    ell = lean_vector(
        np.asarray(toward, np.float64)[None], np.asarray(normal, np.float64)[None], eta
    )  # (1, 3)
    R = np.asarray(R, dtype=np.float64) * use[:, None]
    area = np.asarray(area, dtype=np.float64)
    a = ell @ d_hat.T  # (1, V)
    lean = np.zeros((2, R.shape[1]))
    for _ in range(ROUNDS):  # the band's mean of the shot with the lean found so far taken out
        R0 = symmetric_part(R * np.exp(-lean[0][None, :] * a[0][:, None]), area, r)
        lean = fit_point(R0, R[None], area, a, ell @ normal, r)
    return lean


def fit_lean_from_shots(ds) -> np.ndarray | None:
    """κ and λ per incident point and channel, (P, 2, 3), from a data set of a lab's shots (``import
    object``: each shot's direction toward its laser in the header's ``photographs.toward_laser``); None
    when no shot is more than :data:`~translucency.angles.OBLIQUE_DEG` off the normal."""
    photographs = ds.header.get("photographs") or {}
    if "toward_laser" not in photographs:
        return None
    toward = np.asarray(photographs["toward_laser"], dtype=np.float64)
    frames = ds.incident_frames()
    normals = frames[:, 2]
    oblique = np.flatnonzero(polar_deg(toward, normals) > OBLIQUE_DEG)
    if len(oblique) == 0:
        return None
    eta = float(ds.header.get("boundary_eta", 1.0))
    vertices = np.asarray(ds.group["vertices"][...], dtype=np.float64)
    area = np.asarray(ds.group["vertex_area"][...], dtype=np.float64)
    incident = np.asarray(ds.group["incident"][...])
    lean = np.full((len(incident), 2, 3), np.nan)
    for p in oblique:  # one shot's R_d (V, 3) read at a time
        R = np.asarray(ds.group["R_d"][int(p)], dtype=np.float64)
        lean[p] = lean_of_shot(R, area, vertices, int(incident[p]), normals[p], toward[p], eta)
    # the points lit along their normal: the material's lean, the median of the oblique shots'
    lean[np.isnan(lean[:, 0, 0])] = np.median(lean[oblique], axis=0)
    return lean


__all__ = ["BAND_MM", "fit_lean_from_shots", "lean_of_shot", "symmetric_part"]
