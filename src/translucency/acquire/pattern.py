r"""Virtual DISCO under an arbitrary light pattern: the reference for relighting.

A planar sample lit by an irradiance pattern :math:`E(\vec x)` (W/mm², normal
incidence) over the cells of an incident grid; the radiant exitance of the
diffuse light (Fresnel reflection at entry excluded, as in R_d) is tallied
on a pixel grid of the top surface:

.. math:: B(\vec x_o) \approx \frac{1}{p^2} \sum_{\text{photons} \to \text{pixel}}
          \frac{E_c\, A_c}{K\,N},

for a cell c of area :math:`A_c` lit by :math:`E_c`, entered at K
uniformly jittered points with N photons each.  This is what the fitted
model predicts by :math:`B(\vec x_o) = \alpha(\vec x_o) \sum_i E_i A_i P_i(\vec x_o)`
(:func:`translucency.evaluate.relight.relight`) — computed here by photon
transport, independently of any model.
"""

from __future__ import annotations

import numpy as np

from .._validate import TranslucencyError
from .transport import TOP, random_walk
from .volume import Volume


def acquire_pattern(
    volume: Volume,
    cells: np.ndarray,
    cell_size: float,
    E: np.ndarray,
    origin,
    pitch: float,
    shape: tuple[int, int],
    *,
    photons: int = 2000,
    jitter: int = 4,
    seed: int = 0,
) -> np.ndarray:
    """Radiant exitance of the slab under a light pattern, by photon transport.

    Parameters
    ----------
    volume : Volume
        The sample.
    cells : ndarray, shape (P, 2)
        Centres of the incident cells (mm), squares of side ``cell_size``.
    E : ndarray, shape (P, 3)
        Irradiance on each cell per channel (W/mm², ≥ 0).
    origin, pitch, shape
        The output pixel grid: pixel [row, col] centred at origin + pitch (col + ½, row + ½).
    photons : int
        Photons per jittered entry point and channel.
    jitter : int
        Entry points per lit cell (uniform within the cell).

    Returns
    -------
    B : ndarray, shape (H, W, 3)
        Radiant exitance in W/mm² per unit irradiance.
    """
    E = np.asarray(E, dtype=np.float64)
    cells = np.asarray(cells, dtype=np.float64)
    if E.shape != (len(cells), 3) or (E < 0).any() or not np.isfinite(E).all():
        raise TranslucencyError(
            f"pattern: expected finite irradiance >= 0 of shape {(len(cells), 3)}, got {E.shape}"
        )
    rng = np.random.default_rng(seed)
    h, w = shape
    B = np.zeros((h, w, 3))
    for ch in range(3):
        lit = np.flatnonzero(E[:, ch] > 0)
        if lit.size == 0:
            continue
        entry = (
            np.repeat(cells[lit], jitter, axis=0)
            + (rng.uniform(size=(lit.size * jitter, 2)) - 0.5) * cell_size
        )
        res = random_walk(volume, ch, entry, photons, seed=seed + 7919 * ch)
        weight = np.repeat(E[lit, ch] * cell_size**2 / (jitter * photons), jitter * photons)
        top = res.code == TOP
        col = np.floor((res.x[top] - origin[0]) / pitch).astype(np.int64)
        row = np.floor((res.y[top] - origin[1]) / pitch).astype(np.int64)
        inside = (col >= 0) & (col < w) & (row >= 0) & (row < h)
        B[..., ch] = (
            np.bincount(row[inside] * w + col[inside], weight[top][inside], minlength=h * w).reshape(h, w)
            / pitch**2
        )
    return B
