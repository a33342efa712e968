"""The direction along which an anisotropic model's R_d spreads farthest, per incident point."""

from __future__ import annotations

import numpy as np


def spread_directions(model, channel: int = 1, radius: float = 2.0):
    """Per incident point of an anisotropic exponential model: the direction (radians from x) along which
    its R_d spreads farthest within ``radius`` mm, and the ratio of the rms radii along and across it.

    Direction l's profile P_l(r) = Σ_k c_kl e^{d_kl r} gives ρ_l² = ∫ r² P_l r dr / ∫ P_l r dr over
    r ≤ ``radius`` (the fitted range, where the terms are measured rather than extrapolated); the tensor
    Σ_l ρ_l² u_l u_lᵀ (u_l at θ_l) gives the main axis and the ratio sqrt(λ₁/λ₂).  Isotropic models (and
    m < 3, which cannot tell a direction) give angle 0, ratio 1.
    """
    if model.kind != "exponential" or model.n_directions < 3:
        return np.zeros(model.n_points), np.ones(model.n_points)
    c_blk = model.c[:, channel if model.c.shape[1] == 3 else 0]  # (N, m, n)
    d_blk = model.d[:, channel if model.d.shape[1] == 3 else 0]
    r = (np.arange(200) + 0.5) * radius / 200
    prof = np.einsum("lmk,lmkr->lmr", c_blk, np.exp(d_blk[..., None] * r))  # (N, m, R)
    energy = (prof * r).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        rho2 = np.where(energy > 0, (prof * r**3).sum(-1) / np.where(energy > 0, energy, 1), 0.0)
    theta = 2 * np.pi * np.arange(model.n_directions) / model.n_directions
    txx = (rho2 * np.cos(theta) ** 2).sum(-1)
    tyy = (rho2 * np.sin(theta) ** 2).sum(-1)
    txy = (rho2 * np.cos(theta) * np.sin(theta)).sum(-1)
    angle = 0.5 * np.arctan2(2 * txy, txx - tyy)
    half = np.sqrt((0.5 * (txx - tyy)) ** 2 + txy**2)
    mean = 0.5 * (txx + tyy)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.sqrt((mean + half) / np.maximum(mean - half, 1e-300))
    return angle, ratio
