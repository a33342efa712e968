"""The beam-width correction: a window measured with a beam of finite width → the pencil beam's response."""

from __future__ import annotations

import numpy as np

from ...solvers import fit_exponentials_batched
from .setup import ImportSetup


def beam_correction(val, mask, x_i, origin, setup: ImportSetup) -> np.ndarray:
    r"""A window measured with a beam of finite width, brought to the pencil beam's response.

    A beam of irradiance profile B (normalised, isotropic) measures :math:`M = B * P`, for smooth P
    :math:`M \approx P + \tfrac{\langle\rho^2\rangle}{4} \nabla^2 P` (second order in the beam's
    size; a uniform disc of radius b has :math:`\langle\rho^2\rangle = b^2/2`).  The Laplacian is
    taken from a smooth radial fit of the window itself, two exponentials per channel on its ring
    means, where :math:`\nabla^2 (c e^{-ar}) = c (a^2 - a/r) e^{-ar}` — never from the noisy pixels —
    and :math:`P = M - \tfrac{\langle\rho^2\rangle}{4} \nabla^2 P` is applied at
    :math:`r \ge 2\sqrt{\langle\rho^2\rangle}` (closer, the expansion does not hold; those pixels
    are the beam's own, masked as specular in practice).

    Examples
    --------
    >>> setup = ImportSetup(pitch=0.1, window=4.1, beam_rms=0.2)
    >>> n = setup.window_pixels(); c = (np.arange(n) + 0.5) * 0.1 - 2.05
    >>> r = np.hypot(*np.meshgrid(c, c))
    >>> P = np.exp(-2 * r)[..., None].repeat(3, axis=2)
    >>> M = P * (1 + 0.04 / 4 * (4 - 2 / np.maximum(r, 1e-9)))[..., None]   # what the beam makes of P
    >>> out = beam_correction(M, np.ones((n, n), bool), (0.0, 0.0), (-2.05, -2.05), setup)
    >>> far = r > 0.5
    >>> bool(np.abs(out / P - 1)[far].max() < 0.25 * np.abs(M / P - 1)[far].max())
    True
    """
    m2 = float(setup.beam_rms) ** 2
    n, p = setup.window_pixels(), setup.pitch
    centres = (
        np.asarray(origin, float)[None, None]
        + (np.stack(np.meshgrid(np.arange(n), np.arange(n)), -1) + 0.5) * p
    )
    r = np.hypot(centres[..., 0] - x_i[0], centres[..., 1] - x_i[1])
    r_min = 2.0 * np.sqrt(m2)
    use = mask & (r >= max(r_min, setup.specular_radius, p))
    if use.sum() < 8:
        return val
    # ring means of half-pixel rings, weighted by their pixel counts
    ring = np.floor(r / (p / 2)).astype(int)
    keys, inv = np.unique(ring[use], return_inverse=True)
    count = np.bincount(inv).astype(float)
    r_g = np.bincount(inv, r[use]) / count
    Y = np.stack([np.bincount(inv, val[..., channel][use]) / count for channel in range(3)])
    W = np.broadcast_to(np.sqrt(count), Y.shape)
    c, a, _ = fit_exponentials_batched(r_g, W, Y, 2, n_starts=3)
    rr = np.maximum(r, 1e-9)[..., None, None]  # (n, n, 1, 1) against (3, 2)
    lap = np.sum(c * (a**2 - a / rr) * np.exp(-a * rr), axis=-1)  # (n, n, 3)
    out = np.array(val, dtype=np.float32, copy=True)
    far = r >= r_min
    out[far] = (val[far] - m2 / 4.0 * lap[far]).astype(np.float32)
    return out
