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
  read from Mitsuba's own emitter (float32 included) by :func:`.beam.spot_profile`.
* **camera**: ``orthographic`` along −z, ``hdrfilm`` with a box filter, so a
  pixel's value is the mean radiance :math:`L(\vec x_o, +\hat z)` over its
  footprint; the ``moment`` integrator records each pixel's second moment,
  whence the variance of the pixel mean, :math:`(\overline{L^2} - \bar L^2)/(S-1)`
  for S samples per pixel.

The scene is built by :func:`translucency.mitsuba.scenes.slab_scene`.  Units: mm, and radiance per
unit intensity of the spot (W mm⁻² sr⁻¹ per W sr⁻¹).
"""

from __future__ import annotations

import time

import numpy as np

from .._validate import TranslucencyError
from ..acquire.volume import Volume
from ..mitsuba import NO_ROULETTE, mitsuba, slab_scene
from ._checks import check_channels, check_positive
from .beam import SpotBeam
from .window import PixelWindow, RadianceImage, _check_fits, pixel_centres


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

    Examples
    --------
    >>> slab = Volume.homogeneous((4, 8, 8), 0.5, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3, eta=1.0)
    >>> scene = volpath_scene(slab, 0, SpotBeam((2.0, 2.0)), PixelWindow((2.0, 2.0), n_pixels=4), spp=2)
    >>> len(scene.sensors()), len(scene.emitters()), scene.sensors()[0].film().size().numpy().tolist()
    (1, 1, [4, 4])
    """
    return slab_scene(
        volume, channel, beam.emitter_dict(), window.sensor_dict(spp), rr_depth=rr_depth, moment=True
    )


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

    Examples
    --------
    >>> slab = Volume.homogeneous((4, 8, 8), 0.5, sigma_s=[1.0] * 3, sigma_a=[0.01] * 3, eta=1.0)
    >>> beam, window = SpotBeam((2.0, 2.0)), PixelWindow((2.0, 2.0), n_pixels=4)
    >>> # a variance needs two paths a pixel at least
    >>> render_volpath_spot(slab, beam, window, spp=1)   # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: spp: need an integer of at least 2 samples per pixel ...
    >>> render_volpath_spot(slab, SpotBeam((0.2, 2.0)), window, spp=2)   # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: beam: the lit disc at (0.2, 2.0) mm of radius 0.5 mm ...
    """
    mi = mitsuba()
    _check_fits(volume, beam, window)
    channels = check_channels(channels)
    if check_positive("spp", spp, "samples per pixel") < 2 or spp != int(spp):
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
