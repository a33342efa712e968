r"""Grouping of window pixels by radius, for the fitter.

Every window pixel is a pair :math:`(\vec x_i, \vec x_o)` with distance
:math:`r = |\vec x_o - \vec x_i|` (mm; :func:`translucency.geometry.window_geometry`).
The isotropic objective depends on a pixel only through r, so pixels of equal
r can be merged exactly: for weights :math:`w_j`, coefficients
:math:`\kappa_j` and targets :math:`y_j`,

.. math:: \sum_{j \in g} w_j^2 (\kappa_j f(r_g) - y_j)^2
          = A_g \bigl(f(r_g) - B_g/A_g\bigr)^2 + \text{const},\quad
          A_g = \sum w_j^2 \kappa_j^2,\; B_g = \sum w_j^2 \kappa_j y_j .

Incident points snapped to pixel centres give a few hundred distinct radii
per window instead of thousands of pixels.  Beyond ``r_exact`` radii may
also be merged into rings of width ``radius_step`` (then :math:`r_g` is the
mean radius of the ring — an approximation of relative order
:math:`(a\,\delta r)^2/24` for a term of rate a).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def radius_groups(
    r: np.ndarray, pitch: float, *, r_exact: float | None = None, radius_step: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Group ids (same shape as r), the mean radius of each group and its base radius (mm).

    Radii equal to 1e-4 pixel are one group; beyond ``r_exact`` (default: all
    exact) radii within rings of ``radius_step`` mm are merged.  The base
    radius is the ring's centre (the group's radius where it is exact): equally
    spaced, so the solver can step :math:`e^{-a r}` from ring to ring by a
    product and correct to the mean radius by a short series.

    Examples
    --------
    >>> gid, rg, _ = radius_groups(np.array([[0.0, 1.0, 1.0, 1.5]]), 0.5)
    >>> gid.tolist(), rg.tolist()
    ([[0, 1, 1, 2]], [0.0, 1.0, 1.5])
    """
    key = np.round(r / (pitch * 1e-4)).astype(np.int64)
    if radius_step is not None and r_exact is not None:
        far = r > r_exact
        key = np.where(far, np.int64(2**52) + np.floor(r / radius_step).astype(np.int64), key)
    uniq, gid = np.unique(key, return_inverse=True)
    gid = gid.reshape(r.shape)
    r_g = np.bincount(gid.ravel(), r.ravel(), minlength=uniq.size) / np.bincount(
        gid.ravel(), minlength=uniq.size
    )
    r_base = r_g.copy()
    if radius_step is not None and r_exact is not None:
        # ring centres: equally spaced, on which the solver steps e^{−a r} by one product a ring
        ring = uniq >= 2**52
        r_base[ring] = (uniq[ring] - 2**52 + 0.5) * radius_step
    return gid, r_g, r_base


@dataclass
class Segments:
    r"""Sums over the pixels of each (incident point, key) as contiguous segment sums.

    Every row (incident point) of a chunk has J pixels, each with an integer
    key (its radius group, or direction and radius group); the objective needs
    :math:`\sum_{j:\,\mathrm{key}_j = g} x_{ij}` for every row i and key g.
    Putting each row's pixels in key order (``perm``) makes these sums
    contiguous runs of the flattened (row, pixel) axis, summed by
    ``np.add.reduceat`` — several times faster than a scatter (``bincount``)
    and without a (k, J, 3) index array.

    Examples
    --------
    >>> seg = Segments.of(np.array([[1, 0, 1, 2]]), k=2, n_keys=3)
    >>> seg.sums(np.arange(8.0).reshape(2, 4)).tolist()
    [[1.0, 2.0, 3.0], [5.0, 10.0, 7.0]]
    """

    perm: np.ndarray | None  # (1 or k, J) pixel order within each row; None: already in order
    starts: np.ndarray  # (S,) first flat position (row·J + j, in order) of each non-empty segment
    keys: np.ndarray  # (S,) row·n_keys + key of each segment
    lengths: np.ndarray  # (S,) pixels in each segment
    k: int
    J: int
    n_keys: int

    @classmethod
    def of(cls, key: np.ndarray, k: int, n_keys: int) -> Segments:
        """Segments of keys (1 or k, J) in [0, n_keys); a single row is shared by all k rows."""
        key = np.asarray(key)
        J = key.shape[1]
        perm = None if (np.diff(key, axis=1) >= 0).all() else np.argsort(key, axis=1, kind="stable")
        ks = key if perm is None else np.take_along_axis(key, perm, axis=1)
        if ks.shape[0] == 1:  # one row for all: its runs, repeated
            first = np.flatnonzero(np.r_[True, ks[0, 1:] != ks[0, :-1]])
            starts = (np.arange(k)[:, None] * J + first).ravel()
            keys = (np.arange(k)[:, None] * n_keys + ks[0, first]).ravel()
        else:
            flat = (np.arange(k)[:, None] * n_keys + ks).ravel()
            starts = np.flatnonzero(np.r_[True, flat[1:] != flat[:-1]])
            keys = flat[starts]
        lengths = np.diff(np.r_[starts, k * J])
        return cls(perm, starts, keys, lengths, k, J, n_keys)

    def order(self, x: np.ndarray) -> np.ndarray:
        """x (k or 1, J, ...) with each row's pixels in key order."""
        if self.perm is None:
            return x
        if self.perm.shape[0] == 1:
            return np.take(x, self.perm[0], axis=1)
        p = self.perm.reshape(self.perm.shape + (1,) * (x.ndim - 2))
        return np.take_along_axis(x, np.broadcast_to(p, x.shape[:2] + p.shape[2:]), axis=1)

    def in_order(self) -> Segments:
        """The same segments for arrays already put in key order by :meth:`order`."""
        return Segments(None, self.starts, self.keys, self.lengths, self.k, self.J, self.n_keys)

    def sums(self, x: np.ndarray) -> np.ndarray:
        """Σ of x (k, J) or (k, J, c) over each (row, key): (k, n_keys) or (k, n_keys, c)."""
        flat = self.order(x).reshape(self.k * self.J, -1)
        out = np.zeros((self.k * self.n_keys, flat.shape[1]), dtype=flat.dtype)
        out[self.keys] = np.add.reduceat(flat, self.starts, axis=0)
        return out.reshape((self.k, self.n_keys) + x.shape[2:])

    def spread(self, v: np.ndarray) -> np.ndarray:
        """Values per (row, key) v (k, n_keys, ...) at every pixel, in key order (k, J, ...)."""
        flat = v.reshape(self.k * self.n_keys, -1)[self.keys]
        return np.repeat(flat, self.lengths, axis=0).reshape((self.k, self.J) + v.shape[2:])
