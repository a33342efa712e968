r"""An independent reference for the photon tally: the same slab rendered by Mitsuba 3's ``volpath``.

The set-up is a narrow *spot* light above the slab and an *orthographic*
camera looking straight down at a window of pixels around the beam:

* **slab**: a ``cube`` shape mapped onto the box :math:`[0,W]\times[0,H]\times[-T,0]`
  with a ``null`` BSDF (an index-matched boundary) and, inside, a
  ``heterogeneous`` medium whose extinction :math:`\sigma_t = \sigma_s + \sigma_a`
  and albedo :math:`\sigma_s/\sigma_t` are ``gridvolume`` textures with
  nearest-neighbour lookup, and a Henyey–Greenstein phase function.  One
  channel is rendered at a time as a grey medium, so ``volpath`` uses plain
  delta tracking (no spectral weights).  A dielectric boundary cannot be
  used: next-event estimation cannot reach a point light through a smooth
  interface, so such a slab renders black; Fresnel is validated separately
  (against adding-doubling, ``tests/test_acquire.py``).
* **light**: a ``spot`` emitter of intensity :math:`I = 1` at height
  :math:`D` above the beam centre, pointing down, cut off at
  :math:`\theta_c = \arctan(\rho_b/D)` with Mitsuba's linear falloff from the
  beam width :math:`\tfrac34\theta_c` to :math:`\theta_c`.  The irradiance of
  the plane z = 0 is :math:`E(\rho) = I\,f(\theta)\cos^3\theta/D^2`; it is
  read from Mitsuba's own emitter (float32 included) by :func:`spot_profile`.
* **camera**: ``orthographic`` along −z, ``hdrfilm`` with a box filter, so a
  pixel's value is the mean radiance :math:`L(\vec x_o, +\hat z)` over its
  footprint; the ``moment`` integrator records each pixel's second moment,
  whence the variance of the pixel mean, :math:`(\overline{L^2} - \bar L^2)/(S-1)`
  for S samples per pixel.

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

from .._validate import TranslucencyError, as_float_array
from ..acquire.transport import TOP, random_walk
from ..acquire.volume import Volume
from ..mitsuba import SPOT_BEAM_FRACTION, mitsuba, slab_medium_dict, spot_dict

CAMERA_HEIGHT_MM = 10.0  # orthographic camera plane above the slab (any height > 0 would do)
NO_ROULETTE = 1 << 30  # an rr_depth that volpath never reaches
WALK_BATCH = 8_000_000  # photons per wavefront (about 1 GB of walk state and entry points)


def _point(name: str, value) -> tuple[float, float]:
    """Two finite coordinates (x, y) in mm, or a one-line error."""
    x, y = as_float_array(name, value, shape=(2,))
    return float(x), float(y)


def _positive(name: str, value, unit: str = "mm") -> float:
    """A finite number > 0, or a one-line error naming ``unit``.

    (``_validate.check_positive`` works on arrays and reports an index; this is its scalar form.)
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = float("nan")
    if not (np.isfinite(v) and v > 0):
        raise TranslucencyError(f"{name}: must be a positive number ({unit}), got {value!r}")
    return v


# ------------------------------------------------------------------------------------------------
# geometry: beam and pixel window
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SpotBeam:
    """A spot light at height ``distance_mm`` above ``centre_xy`` (mm), pointing straight down.

    ``radius_mm`` is the radius ρ_b = D tan θ_c of the lit disc on the plane z = 0.
    """

    centre_xy: tuple[float, float]
    radius_mm: float = 0.5
    distance_mm: float = 100.0

    def __post_init__(self):
        object.__setattr__(self, "centre_xy", _point("beam centre", self.centre_xy))
        object.__setattr__(self, "radius_mm", _positive("beam radius", self.radius_mm))
        object.__setattr__(self, "distance_mm", _positive("beam distance", self.distance_mm))
        # float32 resolves cos θ only to ~6e-8, i.e. θ to ~3.5e-4 rad: keep the cutoff well above
        if self.cutoff_deg < 0.2 or self.cutoff_deg > 30.0:
            raise TranslucencyError(
                f"beam radius: {self.radius_mm} mm at {self.distance_mm} mm gives a cutoff of "
                f"{self.cutoff_deg:.3g} deg; keep it within [0.2, 30] deg (float32 angles)"
            )

    @property
    def cutoff_deg(self) -> float:
        """Cutoff angle θ_c of the spot, degrees."""
        return float(np.degrees(np.arctan(self.radius_mm / self.distance_mm)))

    @property
    def beam_width_deg(self) -> float:
        """Angle up to which the intensity is full (Mitsuba's convention, :data:`SPOT_BEAM_FRACTION`)."""
        return SPOT_BEAM_FRACTION * self.cutoff_deg

    def emitter_dict(self, intensity: float = 1.0) -> dict:
        """Mitsuba ``spot`` emitter description."""
        cx, cy = self.centre_xy
        return spot_dict(
            (cx, cy, self.distance_mm), (cx, cy, 0.0), self.cutoff_deg, intensity, up=(0.0, 1.0, 0.0)
        )


@dataclass(frozen=True)
class PixelWindow:
    """A square window of ``n_pixels`` × ``n_pixels`` pixels of side ``pitch_mm`` centred on ``centre_xy``."""

    centre_xy: tuple[float, float]
    n_pixels: int = 16
    pitch_mm: float = 0.25

    def __post_init__(self):
        object.__setattr__(self, "centre_xy", _point("window centre", self.centre_xy))
        n = _positive("window pixels", self.n_pixels, "pixels")
        if n != int(n):
            raise TranslucencyError(f"window pixels: must be a positive integer, got {self.n_pixels!r}")
        object.__setattr__(self, "n_pixels", int(n))
        object.__setattr__(self, "pitch_mm", _positive("pitch", self.pitch_mm))

    @property
    def side_mm(self) -> float:
        return self.n_pixels * self.pitch_mm

    def sensor_dict(self, spp: int = 1) -> dict:
        """Mitsuba ``orthographic`` sensor looking down −z at this window (box filter, RGB film)."""
        mi = mitsuba()
        cx, cy = self.centre_xy
        half = 0.5 * self.side_mm  # the orthographic camera sees [-1, 1]² in its local frame
        to_world = (
            mi.ScalarTransform4f().translate([cx, cy, CAMERA_HEIGHT_MM])
            @ mi.ScalarTransform4f().scale([half, half, 1.0])
            @ mi.ScalarTransform4f().look_at(origin=[0, 0, 0], target=[0, 0, -1], up=[0, 1, 0])
        )
        return {
            "type": "orthographic",
            "to_world": to_world,
            "film": {
                "type": "hdrfilm",
                "width": self.n_pixels,
                "height": self.n_pixels,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": "independent", "sample_count": int(spp)},
        }


def pixel_centres(window: PixelWindow) -> tuple[np.ndarray, np.ndarray]:
    """Centres (x, y) in mm of the window's pixels, shape (n, n) each, indexed [row, column].

    Read from Mitsuba itself: the ray its sensor traces through each pixel
    centre, so the mapping of image rows and columns to the slab does not rest
    on our reading of the orthographic transform.
    """
    mi = mitsuba()
    n = window.n_pixels
    sensor = mi.load_dict(window.sensor_dict())
    col, row = np.meshgrid(np.arange(n), np.arange(n))
    u = ((col + 0.5) / n).ravel().astype(np.float32)
    v = ((row + 0.5) / n).ravel().astype(np.float32)
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(u, v), mi.Point2f(0.5, 0.5))
    x = np.asarray(ray.o.x, dtype=np.float64).reshape(n, n)
    y = np.asarray(ray.o.y, dtype=np.float64).reshape(n, n)
    return x, y


def _check_fits(volume: Volume, beam: SpotBeam, window: PixelWindow) -> None:
    """Beam and window must lie on the top face."""
    W, H, _ = volume.size_mm
    bx, by = beam.centre_xy
    r = beam.radius_mm
    if not (r <= bx <= W - r and r <= by <= H - r):
        raise TranslucencyError(
            f"beam: the lit disc at {beam.centre_xy} mm of radius {r:g} mm does not fit on the "
            f"{W:g} x {H:g} mm top face"
        )
    cx, cy = window.centre_xy
    h = 0.5 * window.side_mm
    if not (h <= cx <= W - h and h <= cy <= H - h):
        raise TranslucencyError(
            f"window: {window.side_mm:g} mm around {window.centre_xy} mm does not fit on the "
            f"{W:g} x {H:g} mm top face"
        )


# ------------------------------------------------------------------------------------------------
# the spot's irradiance on the plane z = 0
# ------------------------------------------------------------------------------------------------


def spot_irradiance(beam: SpotBeam, rho_mm) -> np.ndarray:
    """Irradiance E(ρ) of the plane z = 0 per unit intensity, mm⁻², in float64.

    :math:`E = f(\\theta)\\cos^3\\theta / D^2` with :math:`\\tan\\theta = \\rho/D` and
    Mitsuba's falloff f: 1 up to the beam width θ_w, then linear in θ down
    to 0 at the cutoff θ_c.
    """
    rho = np.asarray(rho_mm, dtype=np.float64)
    D = beam.distance_mm
    theta = np.arctan(rho / D)
    th_c, th_w = np.radians(beam.cutoff_deg), np.radians(beam.beam_width_deg)
    f = np.where(theta <= th_w, 1.0, np.clip((th_c - theta) / (th_c - th_w), 0.0, 1.0))
    return f * np.cos(theta) ** 3 / D**2


def spot_profile(beam: SpotBeam, n_radii: int = 8193) -> tuple[np.ndarray, np.ndarray]:
    """The spot's irradiance E(ρ) on z = 0 as Mitsuba evaluates it, on ``n_radii`` radii.

    Each value is the spot's ``sample_direction`` (I·f/r², float32 as
    rendered) times cos θ = D/r at a point of the plane; the radii run from 0
    to just past the cutoff radius.  Returns (rho (mm), E (mm⁻², float64)).
    """
    mi = mitsuba()
    import drjit as dr  # after mitsuba(): Dr.Jit must load with the libLLVM chosen there

    rho = np.linspace(0.0, beam.radius_mm * 1.02, int(n_radii))
    emitter = mi.load_dict(beam.emitter_dict())
    cx, cy = beam.centre_xy
    it = dr.zeros(mi.Interaction3f, len(rho))
    it.p = mi.Point3f(
        mi.Float((cx + rho).astype(np.float32)),
        mi.Float(np.full(len(rho), cy, np.float32)),
        mi.Float(np.zeros(len(rho), np.float32)),
    )
    _, value = emitter.sample_direction(it, mi.Point2f(0.5, 0.5))
    # distances and cosines in float64 from the points actually queried
    x = np.asarray(it.p.x, dtype=np.float64) - cx
    r = np.hypot(x, beam.distance_mm)
    E = np.asarray(value[0], dtype=np.float64) * beam.distance_mm / r
    return np.abs(x), E


def spot_power(rho: np.ndarray, E: np.ndarray) -> float:
    """Total power P = ∫ E dA = ∫ 2πρ E(ρ) dρ (trapezoid rule, float64), per unit intensity."""
    return float(np.trapezoid(2.0 * np.pi * rho * E, rho))


def sample_spot_entries(beam: SpotBeam, n: int, seed: int, profile=None) -> np.ndarray:
    """``n`` entry points (n, 2) in mm (float32) distributed as the irradiance E(ρ) of the plane z = 0.

    Inverse CDF of :math:`2\\pi\\rho E(\\rho)` (tabulated by :func:`spot_profile`,
    interpolated linearly) for ρ, and a uniform azimuth.
    """
    rho, E = profile if profile is not None else spot_profile(beam)
    dens = 2.0 * np.pi * rho * E
    end = (
        int(np.flatnonzero(dens > 0).max()) + 2
    )  # up to the first zero past the cutoff: a strictly rising CDF
    rho, dens = rho[:end], dens[:end]
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(rho))])
    cdf /= cdf[-1]
    # the inverse CDF on a fine uniform grid of u, then O(1) linear interpolation per sample
    m = 1 << 16
    inv = np.interp(np.linspace(0.0, 1.0, m + 1), cdf, rho)
    rng = np.random.default_rng(seed)
    u = rng.random(n) * m
    i = np.minimum(u.astype(np.int64), m - 1)
    f = u - i
    r = (inv[i] * (1.0 - f) + inv[i + 1] * f).astype(np.float32)
    phi = rng.random(n, dtype=np.float32) * np.float32(2.0 * np.pi)
    # float32 like the walk itself (µm-level rounding on a mm-sized slab); in place, as this runs per photon
    xy = np.empty((n, 2), np.float32)
    for k, (trig, c) in enumerate(((np.cos, beam.centre_xy[0]), (np.sin, beam.centre_xy[1]))):
        trig(phi, out=xy[:, k])
        xy[:, k] *= r
        xy[:, k] += np.float32(c)
    return xy


# ------------------------------------------------------------------------------------------------
# the two estimates of the same radiance image
# ------------------------------------------------------------------------------------------------


@dataclass
class RadianceImage:
    """Radiance L(x_o, +z) leaving the top face, per pixel, per unit intensity of the spot.

    ``radiance`` and ``variance`` (of the estimate) have shape (n, n, C) for the
    C rendered ``channels``; ``x``, ``y`` (n, n) are the pixel centres (mm);
    ``seconds`` is the wall time of the estimate (per channel in ``seconds_per_channel``).
    """

    radiance: np.ndarray
    variance: np.ndarray
    x: np.ndarray
    y: np.ndarray
    channels: tuple[int, ...]
    seconds: float
    seconds_per_channel: tuple[float, ...] = ()


def volpath_scene(
    volume: Volume,
    channel: int,
    beam: SpotBeam,
    window: PixelWindow,
    *,
    spp: int = 1,
    rr_depth: int = NO_ROULETTE,
):
    """The Mitsuba scene: index-matched slab of one channel, spot light, orthographic camera.

    The integrator is ``moment`` around ``volpath`` (unbounded depth); ``rr_depth``
    is the depth where volpath's Russian roulette starts (see :func:`render_volpath_spot`).
    """
    mi = mitsuba()
    W, H, T = volume.size_mm
    slab = mi.ScalarTransform4f().translate([W / 2, H / 2, -T / 2]) @ mi.ScalarTransform4f().scale(
        [W / 2, H / 2, T / 2]
    )
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": {
                "type": "moment",
                "nested": {"type": "volpath", "max_depth": -1, "rr_depth": int(rr_depth)},
            },
            "slab": {
                "type": "cube",
                "to_world": slab,
                "bsdf": {"type": "null"},
                "interior": slab_medium_dict(volume, channel),
            },
            "spot": beam.emitter_dict(),
            "camera": window.sensor_dict(spp),
        }
    )


def _check_channels(channels) -> tuple[int, ...]:
    try:
        ch = tuple(int(c) for c in channels)
    except (TypeError, ValueError):
        ch = ()
    if not ch or any(c not in (0, 1, 2) for c in ch):
        raise TranslucencyError(f"channels: expected a non-empty subset of (0, 1, 2), got {channels!r}")
    return ch


def render_volpath_spot(
    volume: Volume,
    beam: SpotBeam,
    window: PixelWindow,
    spp: int,
    *,
    seed: int = 0,
    channels=(0, 1, 2),
    rr_depth: int = NO_ROULETTE,
) -> RadianceImage:
    """Render the window with Mitsuba's ``volpath``, one grey channel at a time.

    Each pixel value is the mean over ``spp`` paths of the radiance along −z
    through a uniformly sampled point of the pixel (box filter); its variance
    is the sample variance from the ``moment`` integrator's second moment,
    divided by ``spp`` − 1.  Channel c uses seed ``3 seed + c``.

    Russian roulette is off by default.  Mitsuba's roulette (from depth
    ``rr_depth``, Mitsuba's default 5) keeps a path with probability
    min(throughput, 0.95), so where the albedo is close to 1 the weight of a
    surviving path grows as 1/0.95 per event; over the ~100 events of a path
    through a millimetre-sized slab the pixel estimates become heavy-tailed
    and their variance estimates unreliable.

    Returns
    -------
    RadianceImage
        ``seconds`` counts scene loading and rendering (kernels compiled by an
        earlier call with the same structure are reused).
    """
    mi = mitsuba()
    _check_fits(volume, beam, window)
    channels = _check_channels(channels)
    if _positive("spp", spp, "samples per pixel") < 2 or spp != int(spp):
        raise TranslucencyError(
            f"spp: need an integer of at least 2 samples per pixel (for a variance), got {spp!r}"
        )
    n = window.n_pixels
    L = np.zeros((n, n, len(channels)))
    var = np.zeros_like(L)
    per_channel = []
    for k, c in enumerate(channels):
        t0 = time.perf_counter()
        scene = volpath_scene(volume, c, beam, window, spp=int(spp), rr_depth=rr_depth)
        mi.render(scene, spp=int(spp), seed=3 * int(seed) + c)
        bitmap = scene.sensors()[0].film().bitmap()
        names = [f.name for f in bitmap.struct_()]
        data = np.array(bitmap, dtype=np.float64)  # forces evaluation
        per_channel.append(time.perf_counter() - t0)
        # the medium is grey, so the Y (luminance) moments are the radiance moments
        m1 = data[..., names.index("nested.Y")]
        m2 = data[..., names.index("m2_nested.Y")]
        L[..., k] = m1
        var[..., k] = np.maximum(m2 - m1**2, 0.0) / (int(spp) - 1)
    x, y = pixel_centres(window)
    return RadianceImage(L, var, x, y, channels, float(sum(per_channel)), tuple(per_channel))


@dataclass
class TopExits:
    """Photons of one channel that left through the top face: position (mm) and cos θ to +z.

    ``power`` is the beam's total power P (per unit intensity) shared by ``n_photons`` photons.
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
    """
    n = _positive("photons", n_photons, "photons")
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
        np.concatenate(xs), np.concatenate(ys), np.concatenate(cs), n, spot_power(*profile), seconds
    )


def pixel_index(coord: np.ndarray, centres: np.ndarray, pitch_mm: float) -> np.ndarray:
    """Pixel index along one axis from pixel centres ``pitch_mm`` apart (rising or falling); -1 outside.

    The binning rule of :func:`radiance_from_exits`.
    """
    step = pitch_mm if len(centres) < 2 or centres[1] > centres[0] else -pitch_mm
    idx = np.floor((coord - (centres[0] - 0.5 * step)) / step).astype(np.int64)
    return np.where((idx >= 0) & (idx < len(centres)), idx, -1)


def radiance_from_exits(
    exits: TopExits, x: np.ndarray, y: np.ndarray, pitch_mm: float, cone_deg: float
) -> tuple[np.ndarray, np.ndarray]:
    """Radiance image and its variance from top exits within ``cone_deg`` of +z (see module notes).

    ``x``, ``y``: pixel centres (n, n) indexed [row, column], as from :func:`pixel_centres`.
    """
    if not 0.0 < _positive("cone", cone_deg, "degrees") <= 90.0:
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
    """
    _check_fits(volume, beam, window)
    channels = _check_channels(channels)
    x, y = pixel_centres(window)
    profile = spot_profile(beam)
    exits = [walk_spot(volume, beam, c, n_photons, seed=3 * int(seed) + c, profile=profile) for c in channels]
    images = [radiance_from_exits(e, x, y, window.pitch_mm, cone_deg) for e in exits]
    L = np.stack([im[0] for im in images], axis=-1)
    var = np.stack([im[1] for im in images], axis=-1)
    per_channel = tuple(e.seconds for e in exits)
    return RadianceImage(L, var, x, y, channels, float(sum(per_channel)), per_channel), exits


# ------------------------------------------------------------------------------------------------
# comparison
# ------------------------------------------------------------------------------------------------


def z_scores(a: RadianceImage, b: RadianceImage) -> np.ndarray:
    """Per-pixel, per-channel z = (a − b)/sqrt(var_a + var_b); NaN where both variances are 0."""
    if a.radiance.shape != b.radiance.shape:
        raise TranslucencyError(f"images: shapes differ, {a.radiance.shape} and {b.radiance.shape}")
    s = np.sqrt(a.variance + b.variance)
    return np.divide(a.radiance - b.radiance, s, out=np.full(s.shape, np.nan), where=s > 0)


def ring_profile(image: RadianceImage, centre_xy, edges_mm) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean radiance of the pixels whose centres lie in each ring around ``centre_xy``.

    Returns (ring mid-radii (R,), mean (R, C), variance of the mean (R, C)),
    pixels taken as independent; empty rings are NaN.
    """
    edges = np.asarray(edges_mm, dtype=np.float64)
    r = np.hypot(image.x - centre_xy[0], image.y - centre_xy[1])
    ring = np.digitize(r, edges) - 1
    R, C = len(edges) - 1, image.radiance.shape[-1]
    mean = np.full((R, C), np.nan)
    var = np.full((R, C), np.nan)
    for k in range(R):
        m = ring == k
        if m.any():
            mean[k] = image.radiance[m].mean(axis=0)
            var[k] = image.variance[m].sum(axis=0) / m.sum() ** 2
    return 0.5 * (edges[1:] + edges[:-1]), mean, var


@dataclass
class Agreement:
    """How two estimates of the same radiance image agree.

    ``z``: per-pixel, per-channel z-scores where either estimate has a
    variance (flattened); ``ring_*``: ring averages (R, C) around the beam with
    variances and their z-scores ``ring_z``.
    """

    z: np.ndarray
    ring_r: np.ndarray
    ring_ours: np.ndarray
    ring_ours_var: np.ndarray
    ring_ref: np.ndarray
    ring_ref_var: np.ndarray

    @property
    def ring_z(self) -> np.ndarray:
        """(ours − ref)/σ per ring and channel; NaN for empty rings or zero variance."""
        s = np.sqrt(self.ring_ours_var + self.ring_ref_var)
        ok = np.isfinite(s) & (s > 0)
        return np.divide(self.ring_ours - self.ring_ref, s, out=np.full(s.shape, np.nan), where=ok)

    def summary(self) -> dict:
        """Mean and standard deviation of the pixel z-scores, fraction with |z| > 3, and ring χ²/dof."""
        z = self.z
        rz = self.ring_z[np.isfinite(self.ring_z)]
        return {
            "pixels": int(z.size),
            "z_mean": float(z.mean()),
            "z_std": float(z.std()),
            "frac_abs_z_gt_3": float(np.mean(np.abs(z) > 3)),
            "ring_chi2_per_dof": float(np.mean(rz**2)) if rz.size else float("nan"),
        }


def compare(ours: RadianceImage, ref: RadianceImage, centre_xy, ring_edges_mm) -> Agreement:
    """z-scores of ``ours`` against ``ref`` per pixel, and their ring profiles around ``centre_xy``."""
    z = z_scores(ours, ref)
    r, m_o, v_o = ring_profile(ours, centre_xy, ring_edges_mm)
    _, m_r, v_r = ring_profile(ref, centre_xy, ring_edges_mm)
    return Agreement(z[np.isfinite(z)], r, m_o, v_o, m_r, v_r)
