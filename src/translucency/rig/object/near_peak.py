r"""The near peak: R_d of the cells at the laser's hit that no photograph measured (a step of
:mod:`.importer`).

A lab's single exposure clips the spot, and a stated ``spot_radius_mm`` masks it; either way the cells
there (flags :data:`~.fusion.SATURATED`, :data:`~.fusion.SPOT`, and the :data:`~.fusion.UNSEEN` ones
among them) hold a large share of the shot's energy — the steeper the profile, the larger (blue's most).
DISCO kept the peak's local response apart; here it comes from a model of the near peak fitted to the
measured ring around it:

* the **ring**: the measured cells beyond the farthest target cell, out to :data:`RING_MM` further and at
  least :data:`RING_CELLS` of them;
* the **model**: Jensen's dipole profile :math:`s\,R_d^{dip}(r; \sigma_a, \sigma_s', \eta)` with a free
  scale s (three parameters a channel, fitted to the ring's cell means in log space) — or, where it fits
  the ring worse or its whole profile would return more light than came in
  (:math:`s\,R^{dip} > 1`: energy is conserved), the exponential :math:`a e^{-b r}`;
* the **value**: the model's own cell mean :math:`\int \phi_v\, s R_d^{dip}\, dA / A_v` over each target
  cell (:func:`cell_quadrature`, r the distance from the hit, mm);
* its **variance**: half the difference between the two models, squared (the model's form is what is
  least known), plus the ring's relative residual scatter applied to the value.

Units: mm, R_d in mm⁻² per unit incident power.
"""

from __future__ import annotations

import numpy as np

from ...model.dipole import dipole_R_d, dipole_total_reflectance

#: the ring reaches this far beyond the farthest target cell, mm (or further, for :data:`RING_CELLS`)
RING_MM = 2.0
#: the fewest measured cells a ring holds
RING_CELLS = 12
#: sub-triangles a face side of the cells' quadrature (n² centroids a face)
QUADRATURE_N = 6


def subtriangle_centroids(n: int = QUADRATURE_N) -> np.ndarray:
    """Barycentric coordinates (n², 3) of the centroids of a triangle cut into n² equal sub-triangles: a
    rule of equal weights exact for linear functions.

    Examples
    --------
    >>> b = subtriangle_centroids(3)
    >>> b.shape, bool(np.allclose(b.sum(axis=1), 1)), np.round(b.mean(axis=0), 6).tolist()
    ((9, 3), True, [0.333333, 0.333333, 0.333333])
    """
    up = [((i + 1 / 3) / n, (j + 1 / 3) / n) for i in range(n) for j in range(n - i)]
    down = [((i + 2 / 3) / n, (j + 2 / 3) / n) for i in range(n - 1) for j in range(n - 1 - i)]
    ab = np.array(up + down)
    return np.column_stack([ab, 1.0 - ab.sum(axis=1)])


def cell_quadrature(mesh, vertices, n: int = QUADRATURE_N):
    r"""Points and weights over the cells of ``vertices``: for a function f on the surface,
    :math:`\int \phi_v f\, dA \approx \sum_k w_k f(y_k)` over the points k of v, so Σ_k w_k = A_v.

    Returns ``points`` (K, 3) mm, ``weights`` (K,) mm² and ``owner`` (K,): the index into ``vertices``.

    Examples
    --------
    >>> import trimesh
    >>> from translucency.geometry import vertex_areas
    >>> mesh = trimesh.creation.icosphere(2, radius=3.0)
    >>> _, w, owner = cell_quadrature(mesh, [0, 5])
    >>> bool(np.allclose(np.bincount(owner, weights=w), vertex_areas(mesh)[[0, 5]]))
    True
    """
    bary = subtriangle_centroids(n)
    faces = np.asarray(mesh.faces)
    verts = np.asarray(mesh.vertices, dtype=np.float64)
    face_area = np.asarray(mesh.area_faces, dtype=np.float64)
    points, weights, owner = [], [], []
    vertex_faces = mesh.vertex_faces
    for k, v in enumerate(np.asarray(vertices, dtype=np.int64)):
        fs = vertex_faces[v]
        fs = fs[fs >= 0]
        tri = faces[fs]  # (F, 3)
        corner = np.argmax(tri == v, axis=1)  # where v sits in each face
        P = np.einsum("kc,fcd->fkd", bary, verts[tri])  # (F, n², 3)
        phi = bary[:, corner].T  # (F, n²): v's barycentric coordinate at each point
        points.append(P.reshape(-1, 3))
        weights.append((phi * face_area[fs, None] / len(bary)).ravel())
        owner.append(np.full(phi.size, k))
    return np.concatenate(points), np.concatenate(weights), np.concatenate(owner)


def _near_peak_channel(y, r_ring, mean_of, eta):
    """One channel: the dipole fitted to the ring's log cell means ``y``; the target cells' values and
    variances (``mean_of`` gives the cell means of a radial profile, ring cells first)."""
    from scipy.optimize import least_squares  # heavy: SciPy's optimisers load where a peak is recovered

    n_ring = len(y)

    def dipole(x):  # s R_dip(σ_a, σ_s'): parameters log σ_a, log σ_s', log s
        return np.exp(x[2]) * mean_of(lambda d: dipole_R_d(d, np.exp(x[0]), np.exp(x[1]), eta))

    def exponential(x):  # a e^{-b r}: parameters log a, b
        return np.exp(x[0]) * mean_of(lambda d: np.exp(-x[1] * d))

    def residual(model):
        return lambda x: np.log(np.maximum(model(x)[:n_ring], 1e-300)) - y

    sigma_tr = float(np.clip(-np.polyfit(r_ring, y, 1)[0], 1e-3, 50.0))  # from the ring's log slope
    fit = least_squares(
        residual(dipole), [np.log(sigma_tr**2 / 3.0), 0.0, 0.0], bounds=([-12, -6, -20], [6, 6, 20])
    )
    efit = least_squares(residual(exponential), [y.max(), sigma_tr], bounds=([-50, 0], [50, 50]))
    dip, expo = dipole(fit.x)[n_ring:], exponential(efit.x)[n_ring:]
    # the dipole unless it fits the ring worse or its profile would return more light than came in
    albedo = np.exp(fit.x[2]) * float(dipole_total_reflectance(np.exp(fit.x[0]), np.exp(fit.x[1]), eta))
    use_dipole = albedo <= 1.0 and fit.cost <= efit.cost
    value, chosen = (dip, fit) if use_dipole else (expo, efit)
    scatter = float(np.sqrt(np.mean(chosen.fun**2)))  # the ring's relative residual
    return value, (0.5 * (dip - expo)) ** 2 + (scatter * value) ** 2


def recover_near_peak(mesh, hit, R, var, target, measured, eta: float):
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

    Returns
    -------
    R, var : ndarray, shape (V, 3)
        With the target cells' model values and variances.
    recovered : bool
        False where no ring of :data:`RING_CELLS` measured cells surrounds the targets (R, var unchanged).

    Examples
    --------
    A field that is a dipole profile comes back at the hit's cell from its ring:

    >>> import trimesh
    >>> from translucency.geometry import vertex_areas
    >>> mesh = trimesh.creation.icosphere(4, radius=20.0)
    >>> hit = np.asarray(mesh.vertices[0])
    >>> truth = lambda y: dipole_R_d(np.linalg.norm(y - hit, axis=1), 0.05, 1.0, 1.3)
    >>> V = len(mesh.vertices)
    >>> pts, w, owner = cell_quadrature(mesh, np.arange(V))
    >>> mean = np.bincount(owner, w * truth(pts), minlength=V) / np.bincount(owner, w, minlength=V)
    >>> R = np.repeat(mean[:, None], 3, axis=1)
    >>> target = np.arange(V) == 0
    >>> out, v, ok = recover_near_peak(mesh, hit, R * ~target[:, None], 0 * R, target, ~target, 1.3)
    >>> round(float(out[0, 0] / R[0, 0]), 2)
    1.0
    """
    R, var = R.copy(), var.copy()
    targets = np.flatnonzero(target)
    if not len(targets):
        return R, var, True
    verts = np.asarray(mesh.vertices, dtype=np.float64)
    r = np.linalg.norm(verts - hit, axis=1)
    r_in = r[targets].max()
    outside = np.flatnonzero(measured & (r > r_in) & np.all(R > 0, axis=1))
    if len(outside) < RING_CELLS:
        return R, var, False
    order = outside[np.argsort(r[outside])]
    r_out = max(r_in + RING_MM, r[order[RING_CELLS - 1]])
    ring = order[r[order] <= r_out]
    cells = np.concatenate([ring, targets])
    pts, w, owner = cell_quadrature(mesh, cells)
    dist = np.linalg.norm(pts - hit, axis=1)

    def mean_of(profile):  # the cell means (len(cells),) of a radial profile
        return np.bincount(owner, weights=w * profile(dist), minlength=len(cells)) / np.bincount(
            owner, weights=w, minlength=len(cells)
        )

    for ch in range(3):
        value, variance = _near_peak_channel(np.log(R[ring, ch]), r[ring], mean_of, eta)
        R[targets, ch], var[targets, ch] = value, variance
    return R, var, True


__all__ = ["recover_near_peak", "cell_quadrature", "subtriangle_centroids", "RING_MM", "RING_CELLS"]
