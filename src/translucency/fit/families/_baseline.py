"""The baselines: two positive parameters per point and channel, fitted by batched Levenberg–Marquardt.

A baseline family gives its radial profile ``R_d(r, p0, p1, eta)`` (the
parameters (p0, p1) per point and channel in ``state.p``) and its starts; the
physical ones, parametrised by (σ_a, σ_s') in mm⁻¹, have no free amplitude, so
their α keeps the scale (:class:`PhysicalFamily`).
"""

from __future__ import annotations

from abc import abstractmethod
from typing import ClassVar

import numpy as np

from ...solvers import fit_params_batched
from .._pixels import grouped
from ._base import Family


class BaselineFamily(Family):
    """R_d(r; p0, p1, η) per point and channel, the parameters p (P, 3, 2) fitted by batched LM."""

    #: (p0, p1) starts of a cold fit
    starts: ClassVar[list]

    @staticmethod
    @abstractmethod
    def R_d(r, p0, p1, eta):
        """The profile (mm⁻²) at r (mm) of parameters p0, p1 (broadcast) and refractive index η."""

    def params_per_point(self, n_terms, n_directions, colour):
        return 6

    def medium(self, ctx) -> dict:
        """Keywords of :meth:`R_d` and of the model beyond η taken from the fit's medium (e.g. PBD's g)."""
        return {}

    def profiles(self, ctx, params, sl, r_g):
        p = params.p[sl][:, None]  # (k, 1, 3, 2)
        r = r_g[None, :, None]
        return self.R_d(r, p[..., 0], p[..., 1], ctx.eta, **self.medium(ctx))[..., None]

    def fit(self, ctx, state, sl, ch, w2):
        k = ch.y.shape[0]
        W, Y = grouped(ch.rings, ch.r_g.size, 3, w2, ch.alpha, ch.y)
        eta, medium = ctx.eta, self.medium(ctx)

        def profile(r, p):  # R_d per row of p = (p0, p1)
            return self.R_d(r[None, :], p[:, :1], p[:, 1:2], eta, **medium)

        p = state.p[sl].reshape(-1, 2)
        ready = np.repeat(state.ready[sl], 3)
        if ready.any():  # warm: the previous round's parameters, kept unless the refit is better
            p[ready] = fit_params_batched(profile, ch.r_g, W[ready], Y[ready], [p[ready]])[0]
        if (~ready).any():
            pc, _ = fit_params_batched(profile, ch.r_g, W[~ready], Y[~ready], self.starts)
            p[~ready] = pc
        state.p[sl] = p.reshape(k, 3, 2)


class PhysicalFamily(BaselineFamily):
    """A baseline of (σ_a, σ_s') per point and channel (mm⁻¹) and the sample's η: α keeps the scale."""

    keeps_alpha_scale = True
    starts = [(0.01, 1.0), (0.002, 3.0), (0.05, 0.3)]  # (σ_a, σ_s') in 1/mm
    #: the model class built: ``model(x_i, sigma_a, sigma_s_prime, eta, alpha, frame=...)``
    model: ClassVar[type]

    def rescale(self, state, mean):
        """No free amplitude to take α's scale: the α step never asks (``keeps_alpha_scale``)."""
        raise RuntimeError(f"{self.name}: α keeps its scale; the α step does not rescale this family")

    def build(self, ctx, state, alpha, frame):
        p = state.p
        return self.model(ctx.x_i, p[:, :, 0], p[:, :, 1], ctx.eta, alpha, frame=frame, **self.medium(ctx))
