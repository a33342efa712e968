r"""The photon tally's estimate of the radiance image that :mod:`.volpath` renders.

The photon tally (:func:`tally_radiance`) estimates the same quantity from
the walk of :mod:`translucency.acquire.transport` with ``index_matched=True``:
N photons enter at points drawn from :math:`2\pi\rho\,E(\rho)` (each carries
power P/N, :math:`P = \int E\,dA`) going straight down — the beam's tilt of
at most :math:`\theta_c` is ignored: it moves a photon by
:math:`z\tan\theta_c` (5 µm per mm of depth at 0.3°).  The n photons that leave
a pixel of area A through the top face within a cone :math:`\theta < \theta_{cone}`
around +z give

.. math::  \hat L = \frac{P\,n}{N\,A\,\pi\sin^2\theta_{cone}},
           \qquad \operatorname{Var}\hat L
           = \Bigl(\frac{P}{N\,A\,\pi\sin^2\theta_{cone}}\Bigr)^2 n\,(1 - n/N),

since :math:`\int_{cone}\cos\theta\,d\omega = \pi\sin^2\theta_{cone}`.  The
estimate is the cosine-weighted mean of L over the cone: its bias is second
order in :math:`\theta_{cone}`.

Units: mm, and radiance per unit intensity of the spot (W mm⁻² sr⁻¹ per W sr⁻¹).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .._validate import TranslucencyError
from ..acquire.transport import TOP, random_walk
from ..acquire.volume import Volume
from ._checks import check_channels, check_positive
from .beam import SpotBeam, sample_spot_entries, spot_power, spot_profile
from .window import PixelWindow, RadianceImage, _check_fits, pixel_centres

WALK_BATCH = 8_000_000  # photons per wavefront (about 1 GB of walk state and entry points)


@dataclass(kw_only=True)
class TopExits:
    """Photons of one channel that left through the top face: position (mm) and cos θ to +z.

    ``power`` is the beam's total power P (per unit intensity) shared by ``n_photons`` photons.

    Examples
    --------
    >>> exits = TopExits(x=np.array([0.5, 0.6]), y=np.array([0.5, 0.4]), cos_exit=np.array([1.0, 0.5]),
    ...                  n_photons=100, power=1.0, seconds=0.0)
    >>> len(exits.x), exits.power / exits.n_photons   # 2 of 100 photons left the top; each carries P/N
    (2, 0.01)
    """

    x: np.ndarray
    y: np.ndarray
    cos_exit: np.ndarray
    n_photons: int
    power: float
    seconds: float


def walk_spot(
    volume: Volume, beam: SpotBeam, channel: int, n_photons: int, *, seed: int = 0, profile=None
) -> TopExits:
    """Trace ``n_photons`` photons of ``channel`` entering as the spot's irradiance, index-matched.

    Entry points follow :func:`sample_spot_entries` (seed ``seed``); photons
    go straight down (the beam's tilt ≤ θ_c is ignored) and walk in
    wavefronts of at most ``WALK_BATCH`` photons, each batch passing its
    offset as ``first_point`` so that all photons draw from distinct PCG32
    streams.  (Dr.Jit's PCG32 adds the lane index to the seed and sequence
    passed by the walk, so the streams, though distinct, change with the
    batch size: results are the same only statistically.)  The time includes
    sampling the entries.

    Examples
    --------
    >>> from translucency.acquire import Volume
    >>> slab = Volume.homogeneous((4, 8, 8), 0.5, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3, eta=1.0)
    >>> beam = SpotBeam((2.0, 2.0), radius_mm=0.5, distance_mm=100.0)
    >>> exits = walk_spot(slab, beam, 0, 300, seed=1)
    >>> exits.n_photons, 0 < len(exits.x) < 300   # some photons leave through the top, not all
    (300, True)
    >>> bool((exits.cos_exit > 0).all()), bool(((exits.x >= 0) & (exits.x <= 4)).all())  # upward, on the face
    (True, True)
    """
    n = check_positive("photons", n_photons, "photons")
    if n != int(n):
        raise TranslucencyError(f"photons: must be a positive integer, got {n_photons!r}")
    n = int(n)
    t0 = time.perf_counter()
    profile = profile if profile is not None else spot_profile(beam)
    entries = sample_spot_entries(beam, n, seed, profile)
    xs, ys, cs = [], [], []
    for b0 in range(0, n, WALK_BATCH):
        res = random_walk(
            volume, channel, entries[b0 : b0 + WALK_BATCH], 1, seed=seed, first_point=b0, index_matched=True
        )
        top = res.code == TOP
        xs.append(res.x[top].astype(np.float64))
        ys.append(res.y[top].astype(np.float64))
        cs.append(res.cos_exit[top])
    seconds = time.perf_counter() - t0
    return TopExits(
        x=np.concatenate(xs),
        y=np.concatenate(ys),
        cos_exit=np.concatenate(cs),
        n_photons=n,
        power=spot_power(*profile),
        seconds=seconds,
    )


def pixel_index(coord: np.ndarray, centres: np.ndarray, pitch_mm: float) -> np.ndarray:
    """Pixel index along one axis from pixel centres ``pitch_mm`` apart (rising or falling); -1 outside.

    The binning rule of :func:`radiance_from_exits`.

    Examples
    --------
    >>> coord = np.array([0.1, 2.9, 3.1, -0.2])
    >>> pixel_index(coord, np.array([0.5, 1.5, 2.5]), 1.0).tolist()   # rising centres
    [0, 2, -1, -1]
    >>> pixel_index(coord, np.array([2.5, 1.5, 0.5]), 1.0).tolist()   # falling (image rows along −y)
    [2, 0, -1, -1]
    """
    step = pitch_mm if len(centres) < 2 or centres[1] > centres[0] else -pitch_mm
    idx = np.floor((coord - (centres[0] - 0.5 * step)) / step).astype(np.int64)
    return np.where((idx >= 0) & (idx < len(centres)), idx, -1)


def radiance_from_exits(
    exits: TopExits, x: np.ndarray, y: np.ndarray, pitch_mm: float, cone_deg: float
) -> tuple[np.ndarray, np.ndarray]:
    """Radiance image and its variance from top exits within ``cone_deg`` of +z (see module notes).

    ``x``, ``y``: pixel centres (n, n) indexed [row, column], as from :func:`pixel_centres`.

    Examples
    --------
    >>> exits = TopExits(x=np.full(4, 0.5), y=np.full(4, 0.5), cos_exit=np.ones(4), n_photons=100,
    ...                  power=1.0, seconds=0.0)   # 4 of 100 photons leave pixel [0, 0] straight up
    >>> x, y = np.meshgrid([0.5, 1.5], [0.5, 1.5])
    >>> L, var = radiance_from_exits(exits, x, y, pitch_mm=1.0, cone_deg=90.0)
    >>> round(float(L[0, 0]), 6), round(4 / (100 * np.pi), 6), float(L[1, 1])   # P n / (N A π sin²θ)
    (0.012732, 0.012732, 0.0)
    """
    if not 0.0 < check_positive("cone", cone_deg, "degrees") <= 90.0:
        raise TranslucencyError(f"cone: must lie in (0, 90] degrees, got {cone_deg!r}")
    n = x.shape[0]
    keep = exits.cos_exit > np.cos(np.radians(cone_deg))
    col = pixel_index(exits.x[keep], x[0, :], pitch_mm)
    row = pixel_index(exits.y[keep], y[:, 0], pitch_mm)
    ok = (col >= 0) & (row >= 0)
    counts = np.bincount(row[ok] * n + col[ok], minlength=n * n).reshape(n, n).astype(np.float64)
    N = exits.n_photons
    scale = exits.power / (N * pitch_mm**2 * np.pi * np.sin(np.radians(cone_deg)) ** 2)
    return scale * counts, scale**2 * counts * (1.0 - counts / N)


def tally_radiance(
    volume: Volume,
    beam: SpotBeam,
    window: PixelWindow,
    n_photons: int,
    *,
    seed: int = 0,
    channels=(0, 1, 2),
    cone_deg: float = 10.0,
) -> tuple[RadianceImage, list[TopExits]]:
    """The photon tally's estimate of the image that :func:`render_volpath_spot` renders.

    Per channel c, ``n_photons`` photons (seed ``3 seed + c``); the estimator
    and its binomial variance are in the module notes.  Returns the image and
    the top exits per channel (to re-tally with other cones without re-walking).

    Examples
    --------
    >>> from translucency.acquire import Volume
    >>> slab = Volume.homogeneous((4, 8, 8), 0.5, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3, eta=1.0)
    >>> beam, window = SpotBeam((2.0, 2.0)), PixelWindow((2.0, 2.0), n_pixels=4, pitch_mm=0.5)
    >>> image, exits = tally_radiance(slab, beam, window, 300, channels=(1,))
    >>> image.radiance.shape, len(exits), bool((image.variance >= 0).all())
    ((4, 4, 1), 1, True)
    """
    _check_fits(volume, beam, window)
    channels = check_channels(channels)
    x, y = pixel_centres(window)
    profile = spot_profile(beam)
    exits = [walk_spot(volume, beam, c, n_photons, seed=3 * int(seed) + c, profile=profile) for c in channels]
    images = [radiance_from_exits(e, x, y, window.pitch_mm, cone_deg) for e in exits]
    L = np.stack([im[0] for im in images], axis=-1)
    var = np.stack([im[1] for im in images], axis=-1)
    per_channel = tuple(e.seconds for e in exits)
    return RadianceImage(L, var, x, y, channels, float(sum(per_channel)), per_channel), exits
