r"""The radiance of a view (step 3 of :mod:`.importer`) and its cell means per camera (step 4).

One camera's frames of a shot become the radiance per unit laser power at the pixels its map uses,
:math:`L = (Z - \text{dark})/(k\,t\,\text{vig}\,\text{flat})/P` in W mm⁻² sr⁻¹ per W; saturated pixels
are unusable; frames are combined per pixel weighted by exposure time (photon noise); a pixel on the
silhouette is divided by the share of its solid angle on the surface (the background is dark); the
variance is the noise model's — or, where two or more frames share the longest exposure, the larger of it
and the frames' own scatter.  The surface map then takes cell means over each vertex's cell: of L, or of the
exitance :math:`M = \pi L/\gamma(\mu, s, r)` converted pixel by pixel with the exit law γ
(:mod:`.exit_law`).  float32 throughout.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from .exit_law import Lambertian
from .setup import ObjectRig, ObjectShot
from .views import CameraView, read_frame

#: below this γ a pixel is not converted (its exitance would be its noise divided by ~0)
GAMMA_MIN = 1e-3


def view_radiance(shot: ObjectShot, cam: CameraView, rig: ObjectRig):
    """One camera's frames of a shot as radiance per unit power at the pixels its map uses (n, 3), its
    variance, the usable pixels (n,), the least radiance of the pixels every frame clipped (n, 3; 0 for
    the usable) (step 3 of :mod:`.importer`); and the bytes read.  float32 throughout."""
    setup = cam.setup
    rad = setup.radiometry
    shape = (setup.height, setup.width)
    frames = shot.frames.get(setup.name, [])
    used = cam.map.used
    dark, gain = cam.dark_u, cam.gain_u
    num = np.zeros((len(used), 3), np.float32)
    wsum = np.zeros_like(num)
    var_model = np.zeros_like(num)
    longest = max(f.exposure_s for f in frames)
    rep_n = np.zeros(len(used), np.float32)  # repeated frames of the longest exposure: n, Σ L, Σ L²
    rep_s = np.zeros_like(num)
    rep_s2 = np.zeros_like(num)
    floor = np.zeros_like(num)  # where every frame clipped a channel: the radiance it must at least have
    all_clipped = np.ones(num.shape, dtype=bool)
    nbytes = 0
    for f in frames:
        raw = read_frame(f.file, shape, "photograph")
        nbytes += raw.size * 4
        raw = raw[used]
        ok = (raw < rad.saturation).all(axis=1)
        signal = raw - dark
        scale = 1.0 / (gain * np.float32(f.exposure_s * shot.power))  # value → radiance per unit power
        L = signal * scale
        clipped = raw >= rad.saturation
        all_clipped &= clipped
        floor = np.maximum(floor, np.where(clipped, (rad.saturation - dark) * scale, 0.0))
        w = np.float32(f.exposure_s) * ok[:, None]  # photon noise: weight ∝ exposure
        num += w * L
        wsum += w
        var_model += w * w * (rad.gain * np.maximum(signal, 0.0) + rad.read_noise**2) * scale * scale
        if f.exposure_s == longest:
            rep_n += ok
            rep_s += ok[:, None] * L
            rep_s2 += ok[:, None] * L * L
    usable = (wsum > 0).all(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        L = np.where(wsum > 0, num / wsum, 0.0)
        var = np.where(wsum > 0, var_model / (wsum * wsum), 0.0)
        n = rep_n[:, None]
        scatter = (rep_s2 - rep_s * rep_s / n) / (n - 1) / n  # the scatter of the repeated frames' mean
    var = np.where((n >= 2) & np.isfinite(scatter), np.maximum(var, scatter), var)
    floor = np.where(all_clipped & ~usable[:, None], floor, 0.0).astype(np.float32)
    return L, var, usable, floor, nbytes


def shot_cell_means(
    shot: ObjectShot,
    cameras: list[CameraView],
    rig: ObjectRig,
    law=None,
    hit=None,
    *,
    pixels: bool = False,
    aside: dict | None = None,
    view_law=None,
):
    """Per camera: (cell mean (V, 3), its variance, usable weight (V,), mean γ (V, 3), the clipped pixels'
    least value over each cell (V, 3), NaN where none) of the radiance —
    or, with ``law``, of the exitance πL/γ converted pixel by pixel (γ at each pixel's cosine, slant
    and distance from ``hit``: the law varies across a cell near the hit); and the bytes read.  With
    ``pixels`` (and ``law``), also per camera the pixels themselves: (its surface map, the exitance of
    its used pixels (n, 3), its variance, usable (n,), the clipped pixels' least exitance (n, 3)), None
    for a camera without frames — the near peak's evidence (:class:`.pixel_evidence.PixelEvidence`).  The
    cameras run on threads (reading, NumPy and the sparse products release the GIL).  ``aside``: per camera
    name, used pixels (bool) set aside — neither used nor a lower bound where they clip (:mod:`.glint`).
    ``view_law``: γ per camera and pixel instead of ``law``'s (:class:`.walk_law.ShotWalkLaw`)."""
    aside = aside or {}

    def one(indexed):
        c, cam = indexed
        if cam.setup.name not in shot.frames:
            return (None, None), 0
        L, var, usable, floor, nb = view_radiance(shot, cam, rig)
        m = cam.map
        skip = aside.get(cam.setup.name)
        if skip is not None and skip.any():  # unused, and clipped with no bound
            usable = usable & ~skip
            floor = np.where(skip[:, None], np.float32(0.0), floor)
        if m.hit_share is not None:  # a silhouette's pixel: its reading over the part on the surface
            h = np.maximum(m.hit_share[m.used], 1e-6).astype(np.float32)[:, None]
            L, var, floor = L / h, var / (h * h), floor / h
        clipped = ~usable
        if law is None:
            return ((*m.cell_means(L, var, usable), None, _clipped_sum(m, floor, clipped)), None), nb
        u = m.used
        if law.needs_direction:  # the slant and the distance of every pixel used
            r, slant = np.linalg.norm(m.position[u] - hit, axis=1), m.slant(hit, u)
        else:
            r = slant = np.zeros(len(u))
        if view_law is not None:  # the transport's own law, this camera's
            gamma = view_law.pixel_gamma(c, m).astype(np.float32)
        else:
            gamma = law.factor(m.mu[u], slant, r).astype(np.float32)  # (n, 3)
        dark = (gamma <= GAMMA_MIN).any(axis=1)  # a law that sends nothing there (a dielectric at μ ≤ 0)
        if dark.any():
            usable, gamma = usable & ~dark, np.maximum(gamma, np.float32(GAMMA_MIN))
            floor = np.where(dark[:, None], np.float32(0.0), floor)  # and no bound
            clipped = ~usable
        E, vE = np.float32(np.pi) * L / gamma, var * (np.float32(np.pi) / gamma) ** 2
        if isinstance(law, Lambertian):
            g_mean = np.ones((len(m.den), 3), np.float32)
        else:
            g_mean = m.cell_means(gamma, np.zeros_like(gamma), usable)[0]
        E_floor = np.float32(np.pi) * floor / gamma
        view = (m, E, vE, usable, E_floor) if pixels else None
        return ((*m.cell_means(E, vE, usable), g_mean, _clipped_sum(m, E_floor, clipped)), view), nb

    with ThreadPoolExecutor(min(len(cameras), os.cpu_count() or 1)) as pool:
        results = list(pool.map(one, enumerate(cameras)))
    per_cam = [r for (r, _), _ in results]
    nbytes = sum(nb for _, nb in results)
    if pixels:
        return per_cam, [v for (_, v), _ in results], nbytes
    return per_cam, nbytes


def _clipped_sum(m, floor, clipped) -> np.ndarray:
    """Per cell (V, 3): the clipped pixels' least value summed over the part of the cell they cover (their
    mean there times that area, mm²; 0 where none clipped) — a cell's least mean is this over its area,
    the rest of it at least 0 (:func:`.fusion.fuse`): the clipped pixels' mean alone is no bound on a cell
    they cover in part."""
    mean, _, covered = m.cell_means(floor, 0 * floor, clipped)
    return np.nan_to_num(mean * covered[:, None])
