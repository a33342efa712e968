r"""The path-traced reference of a scene with fitted objects: the same scene, file and camera, with each
fitted object's volume in place of its glowing surface, rendered by Mitsuba's ``volpath``.

Each fitted shape becomes a ``ply`` of the same triangles holding the heterogeneous medium of its data
set's filling (:func:`translucency.render.volume_of_dataset`, carried by the object's pose) behind a
``null`` boundary (index-matched) or a smooth ``dielectric`` of its η; the scene's own emitters, shapes
and sensor are kept, the whole carried into millimetres around the objects
(:mod:`translucency.mitsuba.scene_frame`: in a scene in metres Mitsuba's ray offset is 0.09 mm of the
object, and volpath would skip that much of the medium and lose a nearby lamp to its shadow rays); the
integrator is ``volpath`` without a depth limit and with Russian roulette only from depth
:data:`RR_DEPTH`.  One grey channel of the media at a time, as
:func:`translucency.render.render_reference` does.  A dielectric object reached by delta lights only
(point, spot, directional) cannot be path-traced: a delta refraction is a path ``volpath`` cannot sample.

:func:`converged_scene_reference` renders it twice with independent seeds and returns the mean and its
measured noise over given pixels,
:math:`\varepsilon = \lVert A - B \rVert / (2 \lVert (A + B)/2 \rVert)`.
"""

from __future__ import annotations

import time

import numpy as np

from ..mitsuba import mitsuba, slab_medium_dict
from ..mitsuba.scene_frame import SceneFrame
from ..mitsuba.user_scenes import user_scene_with_media
from ..render import volume_of_dataset
from ..render.reference import mean_of_halves

#: Russian roulette in the reference only past this depth (the surfaces of the scene end most paths)
RR_DEPTH = 1000


def reference_frame(fitted_scene) -> SceneFrame:
    """Millimetres around the fitted objects (the centre of their boxes): where the reference is traced
    whatever the scene's unit and wherever its objects stand (:mod:`translucency.mitsuba.scene_frame`)."""
    units = {float(o.scene_unit_mm) for o in fitted_scene.objects}
    if len(units) != 1:  # (FittedScene gives every object the scene's one unit)
        raise ValueError(f"the fitted objects disagree on the scene's unit: {sorted(units)}")
    everything = np.concatenate([o.vertices for o in fitted_scene.objects])
    return SceneFrame(units.pop(), 0.5 * (everything.min(axis=0) + everything.max(axis=0)))


def _media(fitted_scene, volumes, channel: int, frame: SceneFrame) -> dict:
    """Each fitted object's volume (``volumes``, in the objects' order) behind its boundary, in ``frame``
    (mm: coefficients per mm)."""
    out = {}
    for o, volume in zip(fitted_scene.objects, volumes):
        lo, hi = o.mesh.bounds
        placed = frame.matrix @ o.pose.matrix  # model mm → scene units → the frame's mm
        medium = slab_medium_dict(volume, channel, (lo[0], lo[1], hi[2]), placed=placed, unit_mm=1.0)
        boundary = (
            {"type": "null"}
            if o.eta == 1.0
            else {"type": "dielectric", "int_ior": float(o.eta), "ext_ior": 1.0}
        )
        mesh = (frame.points(o.vertices), np.asarray(o.mesh.faces))
        out[o.name] = {"mesh": mesh, "bsdf": boundary, "interior": medium}
    return out


def render_scene_reference(fitted_scene, *, spp: int = 64, seed: int = 0, sensor: int = 0):
    """The reference picture (H, W, 3) of ``fitted_scene``'s scene (module docstring) and the seconds the
    path tracing took."""
    mi = mitsuba()
    integrator = {"type": "volpath", "max_depth": -1, "rr_depth": RR_DEPTH}
    frame = reference_frame(fitted_scene)
    volumes = [volume_of_dataset(o.mesh, o.acquisition) for o in fitted_scene.objects]  # once, not a channel
    seconds, channels = 0.0, []
    for ch in range(3):
        media = _media(fitted_scene, volumes, ch, frame)
        scene = user_scene_with_media(fitted_scene.source, media, integrator, frame)
        t = time.perf_counter()
        image = mi.render(scene, spp=int(spp), seed=3 * int(seed) + ch, sensor=int(sensor))
        channels.append(np.asarray(image, dtype=np.float64)[..., ch])
        seconds += time.perf_counter() - t
    return np.stack(channels, axis=2), seconds


def converged_scene_reference(fitted_scene, mask: np.ndarray, *, spp: int = 64, sensor: int = 0):
    """The mean of two independent references and its measured noise over ``mask`` (module docstring;
    :func:`translucency.render.reference.mean_of_halves`).

    Returns (image (H, W, 3), info: ``noise``, ``single`` (one render's error), ``spp`` of each render,
    ``seconds`` (both), ``seconds_each``)."""
    a, ta = render_scene_reference(fitted_scene, spp=spp, seed=0, sensor=sensor)
    b, tb = render_scene_reference(fitted_scene, spp=spp, seed=1, sensor=sensor)
    mean, noise, single = mean_of_halves(a, b, mask)
    info = {"noise": noise, "single": single, "spp": int(spp), "renders": 2, "seconds": ta + tb}
    return mean, {**info, "seconds_each": [ta, tb]}
