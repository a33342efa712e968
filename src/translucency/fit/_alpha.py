r"""The α step of a round: the modulation texture in closed form from the round's statistics.

α_j = Σ w² P y / Σ w² P² per pixel (pooled over neighbours on meshes), then
mean α = 1 over the observed pixels, the profiles' amplitudes taking the scale so
that αP (and Φ) are unchanged (:attr:`Family.keeps_alpha_scale`: the families
without a free amplitude keep α's scale).  Φ of the new state is exact without a
further pass: Φ is quadratic in each α_j (:func:`update_alpha`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # annotations only
    from .families import Family
    from .state import FitState


def update_alpha(state: FitState, family: Family, smooth=None) -> float:
    r"""α_j = Σ w²Py / Σ w²P² from the round's statistics, then mean α = 1 with the scale moved into P.

    Returns the change of Φ that the new α makes against the round's α: Φ is quadratic in each
    α_j with minimum at :math:`\alpha^*_j = N_j/D_j` (N = Σ w²Py, D = Σ w²P²), so
    :math:`\Phi(\alpha) - \Phi(\alpha') = \sum_j D_j[(\alpha_j - \alpha^*_j)^2 - (\alpha'_j - \alpha^*_j)^2]`
    exactly, for any α (smoothed, clipped at 0) — and free of the cancellation of expanding Φ.
    """
    num, den = state.num, state.den  # summed in chunk order (FitState.add): deterministic
    seen = den > 0
    best = np.where(seen, num / np.where(seen, den, 1.0), 1.0)  # α* per pixel
    shown = seen
    alpha = best
    if smooth is not None:  # pool the statistics of neighbouring outgoing points (meshes)
        s_num, s_den = smooth(num), smooth(den)
        shown = s_den > 0
        alpha = np.where(shown, s_num / np.where(shown, s_den, 1.0), 1.0)
    alpha = np.maximum(alpha, 0.0)
    old, new = state.alpha[seen], alpha[seen]
    change = float(np.sum(den[seen] * ((new - best[seen]) ** 2 - (old - best[seen]) ** 2)))
    # mean α = 1 over the observed pixels, the profiles' amplitudes take the scale (α P unchanged,
    # so Φ too); a family without a free amplitude (σ_a, σ_s') leaves α its scale
    if not family.keeps_alpha_scale and shown.any():
        mean = float(alpha[shown].mean())
        if mean > 0:
            alpha = np.where(shown, alpha / mean, 1.0)
            family.rescale(state, mean)
    state.alpha[...] = alpha
    state.num[...] = 0.0
    state.den[...] = 0.0
    return change
