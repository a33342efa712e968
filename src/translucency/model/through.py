r"""Light through the body: a measured correction of the radial profile by the pair's orientation.

The paper's per-vertex model is a radial profile of the straight-line distance,
:math:`R_d(x_i, x_o) = \alpha(x_o) P_i(|x_o - x_i|)`.  On a small object of a clear material one profile
cannot be both the light along the front surface and the light through the body at the same distance:
on a 27 mm marble cow (issue 24) the fitted profile carries 0.45 / 0.57 / 0.79 (R/G/B) of the measured
energy of the pairs whose normals face apart (:math:`n_i \cdot n_o < -0.5`) and 1.5–12× the measured
energy of the pairs 10–25 mm apart on the same side — a back-lit object is drawn 40 % too dark and
too grey.

The extension keeps the profile and multiplies it by a table per incident point and channel,

.. math:: R_d^{through}(x_i, x_o) = k_i(n_i \cdot n_o,\ |x_o - x_i|)\; \alpha(x_o) P_i(|x_o - x_i|),

with :math:`k_i` the ratio of the measured to the modelled energy, :math:`\sum A_o R_d^{meas} / \sum A_o
R_d^{model}`, over the pairs in each cell of a grid in the cosine between the two normals (4 cells) and
the distance (:data:`R_EDGES`, mm), pooled over the nearest incident points so that the far, dim cells
are not photon noise (:func:`translucency.fit.through.measure_through`).  Between cell centres k is
interpolated linearly in the cosine and in log r; a cell without pairs keeps 1.  The
renderer then normalises each kernel to the measured total as before, so the table moves light
between the sides of the body and does not add any.
"""

from __future__ import annotations

import numpy as np

#: the cells' edges in the cosine between the normals n_i · n_o
COS_EDGES = np.array([-1.0, -0.5, 0.0, 0.5, 1.0])
#: the cells' edges in the distance, mm (log-spaced: the profile's scale changes with r)
R_EDGES = np.array([0.0, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, np.inf])
#: k is kept within [1 / K_LIMIT, K_LIMIT]
K_LIMIT = 8.0


def _centres():
    c = 0.5 * (COS_EDGES[:-1] + COS_EDGES[1:])
    r = np.sqrt(np.maximum(R_EDGES[:-1], 0.5) * np.minimum(R_EDGES[1:], 2 * R_EDGES[-2]))  # geometric
    return c, np.log(r)


def cells(cos, r):
    """The cell (cos index, r index) of each pair, for tabulating (ints of the shape of ``cos``)."""
    ic = np.clip(np.searchsorted(COS_EDGES, cos, side="right") - 1, 0, len(COS_EDGES) - 2)
    ir = np.clip(np.searchsorted(R_EDGES, r, side="right") - 1, 0, len(R_EDGES) - 2)
    return ic, ir


def through_factor(table, src, cos, r) -> np.ndarray:
    r""":math:`k(n_i \cdot n_o, r)` per pair, bilinear between cell centres (in cos and log r), clamped at
    the outer centres.

    Parameters
    ----------
    table : ndarray, shape (S, 4, 8)
        The sources' tables (one channel).
    src : ndarray of int, shape (M,)
        Each pair's source, an index into ``table``.
    cos, r : ndarray, shape (M,)
        The pairs' cosines between the normals and distances (mm).

    Examples
    --------
    >>> t = np.ones((1, 4, 8))
    >>> float(through_factor(t, np.array([0]), np.array([0.3]), np.array([5.0]))[0])
    1.0
    """
    nodes, weights = interpolation_nodes(cos, r)
    flat = table.reshape(len(table), -1)
    return np.einsum("mq,mq->m", weights, flat[np.asarray(src)[:, None], nodes])


def interpolation_nodes(cos, r):
    """The four cell centres (flat indices into a (4, 8) table) each pair interpolates, and their bilinear
    weights (in cos and log r, clamped at the outer centres): two (M, 4) arrays."""
    cc, lr = _centres()
    fc = np.interp(np.clip(cos, cc[0], cc[-1]), cc, np.arange(len(cc)))
    fr = np.interp(np.log(np.maximum(r, 1e-6)), lr, np.arange(len(lr)))
    ic = np.minimum(fc.astype(np.int64), len(cc) - 2)
    ir = np.minimum(fr.astype(np.int64), len(lr) - 2)
    tc, tr = fc - ic, fr - ir
    Br = len(lr)
    base = ic * Br + ir
    nodes = np.stack([base, base + 1, base + Br, base + Br + 1], axis=1)
    weights = np.stack([(1 - tc) * (1 - tr), (1 - tc) * tr, tc * (1 - tr), tc * tr], axis=1)
    return nodes, weights
