r"""Direction weights :math:`w_l(\vec x_i, \vec x_o)` of the anisotropic model.

The paper fits one set of parameters per direction between :math:`\vec x_i`
and :math:`\vec x_o` and blends their contributions with weights :math:`w_l`.
We place the :math:`m` directions at the angles

.. math:: \theta_l = 2\pi l / m, \qquad l = 0, \dots, m-1

of the tangent frame at :math:`\vec x_i` (``l = 0`` is the frame's first
tangent axis; the paper's ``l = m`` is our ``l = 0``) and blend the two nearest
directions by linear interpolation in angle: the hat function

.. math:: w_l(\theta) = \max\bigl(0,\; 1 - |\theta \ominus \theta_l| / \Delta\bigr),
          \qquad \Delta = 2\pi/m,

where :math:`\ominus` is the difference wrapped to :math:`(-\pi, \pi]`.  The
weights are non-negative, sum to one for every :math:`\theta` (a partition of
unity) and are continuous across :math:`\theta = 0 = 2\pi`.  Each weight
integrates to :math:`\int_0^{2\pi} w_l\,d\theta = \Delta`, which the analytic
helpers of :mod:`translucency.model.exponential` rely on.  For ``m = 1`` the
model is isotropic and :math:`w_1 \equiv 1`.
"""

from __future__ import annotations

import numpy as np

TWO_PI = 2.0 * np.pi


def direction_angles(m: int) -> np.ndarray:
    """Angles :math:`\\theta_l = 2\\pi l/m` of the ``m`` model directions, in radians.

    Examples
    --------
    >>> direction_angles(4) / np.pi
    array([0. , 0.5, 1. , 1.5])
    """
    return TWO_PI * np.arange(m) / m


def direction_weights(theta, m: int) -> np.ndarray:
    """Blend weights :math:`w_l(\\theta)` for ``m`` directions.

    Parameters
    ----------
    theta : array_like, shape (...)
        Angle of :math:`\\vec x_o - \\vec x_i` in the tangent frame at
        :math:`\\vec x_i`, in radians (any range).
    m : int
        Number of directions; ``m = 1`` is the isotropic model.

    Returns
    -------
    w : ndarray, shape (..., m)
        Non-negative weights summing to one along the last axis.

    Examples
    --------
    >>> direction_weights(np.pi / 8, 8).round(3)  # halfway between l=0 and l=1
    array([0.5, 0.5, 0. , 0. , 0. , 0. , 0. , 0. ])
    """
    theta = np.asarray(theta, dtype=np.float64)
    if m == 1:
        return np.ones(theta.shape + (1,))
    # position in units of the direction spacing Δ: between l0 and l0 + 1 (mod m)
    u = np.mod(theta / (TWO_PI / m), m)
    l0 = np.floor(u)
    t = u - l0  # fraction of the way to the next direction
    l0 = l0.astype(np.int64) % m
    w = np.zeros(theta.shape + (m,))
    np.put_along_axis(w, l0[..., None], (1.0 - t)[..., None], axis=-1)
    np.put_along_axis(w, ((l0 + 1) % m)[..., None], t[..., None], axis=-1)
    return w


def sample_direction_offset(u, m: int) -> np.ndarray:
    """Sample an angle offset from the hat :math:`w_l` around its direction.

    Inverts the CDF of the triangular density :math:`w_l(\\theta)/\\Delta` on
    :math:`[\\theta_l - \\Delta, \\theta_l + \\Delta]`.  For ``m = 1`` the
    density is uniform over the circle.

    Parameters
    ----------
    u : array_like
        Uniform numbers in [0, 1).
    m : int
        Number of directions.

    Returns
    -------
    offset : ndarray
        :math:`\\theta - \\theta_l` in radians.
    """
    u = np.asarray(u, dtype=np.float64)
    if m == 1:
        return TWO_PI * u
    delta = TWO_PI / m
    # inverse CDF of the symmetric triangle on [-1, 1]
    t = np.where(u < 0.5, np.sqrt(2.0 * u) - 1.0, 1.0 - np.sqrt(2.0 * (1.0 - u)))
    return t * delta
