r"""The pixels that see the near peak: the misfit of a radial profile against what they read
(:class:`PixelEvidence`, a step of :mod:`.near_peak`).

Units: mm, R_d in mm⁻² per unit incident power; a pixel's reading in the same units (exitance per unit
power over its footprint).
"""

from __future__ import annotations

import numpy as np

from ...acquire.mesh import exit_barycentric
from .surface_map import GRAZING_DEG

#: the profile's form is known to this relative error (a bright pixel's weight is capped by it)
MODEL_FLOOR = 0.05
#: a near-peak model reading below this share of the clipped pixels' value (median) cannot hold the peak
CLIP_REACH = 0.8
#: rays a pixel side when the near peak's pixels are sampled again
PIXEL_SUB = 8
#: a ray this many footprint radii from the hit or nearer reads the mean of the profile over its footprint
CORE_FOOTPRINTS = 3.0
#: points of equal area over the unit disc (a sunflower): a footprint's mean
_DISC = (
    lambda k: (
        np.sqrt((k + 0.5) / len(k))[:, None]
        * np.column_stack([np.cos(k * 2.39996323), np.sin(k * 2.39996323)])
    )
)(np.arange(64.0))


class PixelEvidence:
    r"""The pixels whose whole footprint lies within ``r_zone`` of the hit, seen within
    :data:`~.surface_map.GRAZING_DEG` of the normal, one channel at a time: the misfit of a radial
    profile f against them.

    A pixel reads the solid-angle mean of what its rays see, :math:`m_p = \sum_s \Omega_s G_s f(|y_s -
    x_i|) / \sum_s \Omega_s` over its sub-pixel rays s that meet the mesh
    (:attr:`.surface_map.SurfaceMap.rays`, grazing ones included; G_s the cells' gains,
    :mod:`.shape_gain`, interpolated over the ray's face, 1 without) — exact for a profile as steep as the
    near peak, where interpolating cell means would not be, and for a pixel that sees the surface at
    grazing angles in part, where a footprint-weighted mean would not be.  Usable pixels give
    :math:`(m_p - E_p)/\sqrt{\mathrm{Var}\,E_p + (\epsilon E_p)^2}` (ε = :data:`MODEL_FLOOR`: the
    profile's form is known to a few per cent, not to the photon noise of a bright pixel); clipped ones
    count only where the profile falls below what they show,
    :math:`\min(0, m_p - E^{clip}_p)/(\epsilon E^{clip}_p)`.

    The map's rays (a few a pixel, enough for its cells) are too few for a pixel over the peak: with
    ``sample`` (a function of a map and pixels giving the rays of those pixels, as :attr:`rays`) the kept
    pixels are sampled again, :data:`PIXEL_SUB` × :data:`PIXEL_SUB` rays each; a ray within
    :data:`CORE_FOOTPRINTS` of its footprint's radius of the hit reads the profile's mean over its
    footprint (a disc of the same area).
    """

    def __init__(self, views, hit, r_zone: float, mesh=None, sample=None):
        self.parts, self.cells, self.radii, self.points = [], [], [], []
        for m, E, var, usable, floor in views:
            pixel, y, omega, a_s, face = m.rays  # each ray's solid angle (its reading's weight), footprint
            n = len(m.used)
            col = np.minimum(np.searchsorted(m.used, pixel), n - 1)  # each ray's pixel among the used ones
            read = m.used[col] == pixel  # (a pixel whose rays all graze is not read: no value to fit)
            pixel, y, omega, a_s, face, col = (a[read] for a in (pixel, y, omega, a_s, face, col))
            r_s = np.linalg.norm(y.astype(np.float64) - hit, axis=1)
            far = np.bincount(col, weights=(r_s > r_zone).astype(float), minlength=n) > 0
            clipped = ~usable & (floor > 0).any(axis=1)
            inside = np.bincount(col, minlength=n) > 0
            # a pixel seen at a grazing angle (its centre's) is left out, as the cells' fusion leaves it out:
            # there the exit law is least known and a footprint longest
            facing = m.mu[m.used] > np.cos(np.radians(GRAZING_DEG))
            keep = inside & ~far & facing & (usable | clipped)
            if not keep.any():
                continue
            if sample is not None:  # the kept pixels sampled finely: a few rays miss the core's share
                pixel, y, omega, a_s, face = sample(m, m.used[keep])
                col = np.searchsorted(m.used, pixel)
                r_s = np.linalg.norm(y.astype(np.float64) - hit, axis=1)
            rays = keep[col]
            index = np.cumsum(keep) - 1  # the kept pixels renumbered
            self.parts.append(
                (
                    index[col[rays]],
                    r_s[rays],
                    omega[rays].astype(np.float64),
                    int(keep.sum()),
                    E[keep],
                    var[keep],
                    usable[keep],
                    floor[keep],
                )
            )
            # each ray's face's corners and its barycentric weights there: where the cells' gains multiply
            # the profile (the face, not the nearest vertex: across a sheet thinner than a cell that is
            # the far side's)
            self.cells.append(exit_barycentric(mesh, face[rays], y[rays]) if mesh is not None else None)
            self.radii.append(np.sqrt(a_s[rays].astype(np.float64) / np.pi))  # its footprint's radius, mm
            self.points.append((y[rays].astype(np.float64), self.radii[-1]))
        self.channel = 0
        #: (V, 3) per-cell gains of the profile (:mod:`.shape_gain`), or None
        self.gain = None
        #: per channel the power of light leaving at one point (:meth:`delta`), and the pixels that see it
        self.deltas, self.delta_pixels = [None, None, None], None

    def __bool__(self):
        return bool(self.parts)

    def delta(self, ch: int, point, power: float) -> None:
        """Light of ``power`` (per unit incident) leaving at one ``point`` (mm), in channel ``ch``: the
        pixel whose rays come nearest it (within two of their footprint radii) reads power / its
        footprint's area; the others nothing."""
        if point is None or power <= 0:
            self.deltas[ch] = None
            return
        if self.delta_pixels is None:  # where the point is seen: the same for every σ_t
            self.delta_pixels = []
            for (col, *_), (y, rho) in zip(self.parts, self.points):
                d = np.linalg.norm(y - point, axis=1)
                s = int(np.argmin(d))
                if d[s] > 2 * rho[s]:
                    self.delta_pixels.append(None)
                    continue
                p = col[s]
                self.delta_pixels.append((p, 1.0 / float(np.pi * np.sum(rho[col == p] ** 2))))
        self.deltas[ch] = power

    def _readings(self, profile):
        """Each kept pixel's reading of ``profile``: Σ_s Ω_s G_s f(r_s) / Σ_s Ω_s (plus the point of
        unscattered light, :meth:`delta`), per camera."""
        power = self.deltas[self.channel]
        for k, ((col, r_s, omega, n, *_), cell, rho) in enumerate(zip(self.parts, self.cells, self.radii)):
            f = profile(r_s)
            core = r_s < CORE_FOOTPRINTS * rho  # the 1/r core within a footprint or two: its disc's mean
            if core.any():
                d = np.hypot(r_s[core, None] + rho[core, None] * _DISC[:, 0], rho[core, None] * _DISC[:, 1])
                f[core] = profile(d.ravel()).reshape(d.shape).mean(axis=1)
            if self.gain is not None and cell is not None:
                tri, bary = cell
                f = f * np.einsum("ij,ij->i", bary, self.gain[tri, self.channel])
            m = np.bincount(col, weights=omega * f, minlength=n) / np.bincount(col, omega, minlength=n)
            seen = self.delta_pixels[k] if power and self.delta_pixels else None
            if seen is not None:  # the point of unscattered light, in the one pixel that sees it
                m[seen[0]] += power * seen[1]
            yield m

    def short_of_clip(self, profile) -> bool:
        """Whether the profile reads below :data:`CLIP_REACH` of what the clipped pixels show (median over
        them): the near peak is steeper than any half-space's (a horn's tip, a thin part)."""
        ratios = []
        for part, m in zip(self.parts, self._readings(profile)):
            usable, floor = part[6], part[7]
            f = floor[:, self.channel]
            clip = ~usable & (f > 0)
            ratios.append(m[clip] / f[clip])
        ratios = np.concatenate(ratios) if ratios else np.zeros(0)
        return bool(len(ratios)) and float(np.median(ratios)) < CLIP_REACH

    def relative_scatter(self, profile) -> float:
        r"""The usable pixels' relative scatter about ``profile`` beyond their own noise,
        :math:`\big(\sum_p w_p (\rho_p^2 - v_p) / \sum_p w_p\big)^{1/2}` with
        :math:`\rho_p = (m_p - E_p)/E_p`, :math:`v_p = \mathrm{Var}\,E_p / E_p^2` and
        :math:`w_p = 1/(v_p + \epsilon^2)` (0 where the noise explains it all)."""
        num = den = 0.0
        for (*_, E, var, usable, _floor), m in zip(self.parts, self._readings(profile)):
            e = E[usable, self.channel].astype(np.float64)
            ok = e > 0
            e, mm = e[ok], m[usable][ok]
            v = np.maximum(var[usable, self.channel][ok], 0) / e**2
            w = 1.0 / (v + MODEL_FLOOR**2)
            num += float(w @ (((mm - e) / e) ** 2 - v))
            den += float(w.sum())
        return float(np.sqrt(max(num, 0.0) / den)) if den > 0 else 0.0

    def __call__(self, profile):
        ch, out = self.channel, []
        for (*_, E, var, usable, floor), m in zip(self.parts, self._readings(profile)):
            e, f = E[:, ch], floor[:, ch]
            scale = np.sqrt(np.maximum(var[:, ch], 0) + (MODEL_FLOOR * e) ** 2) + 1e-30
            out.append(np.where(usable, (m - e) / scale, 0.0))
            clip = ~usable & (f > 0)
            out.append(np.where(clip, np.minimum(0.0, m - f) / (MODEL_FLOOR * f + 1e-30), 0.0))
        return np.concatenate(out)
