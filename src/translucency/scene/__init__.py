"""Fitted objects in a user's own Mitsuba 3 scene: lit by every emitter, shadowed and lit by every other
shape, lighting them back, seen through the scene's camera.

:mod:`.pose` (where the model's mesh stands) → :mod:`.fitted` (an object: model, transport, boundary) →
:mod:`.surfaces` (the objects as glowing surfaces: evaluated and sampled) → :mod:`.integrator` (the path
tracer) → :mod:`.irradiance` (the light at the vertices) → :mod:`.fitted_scene` (prepare, light, render);
:mod:`.plugin` registers it with Mitsuba; :mod:`.reference` and :mod:`.compare` check it against ``volpath``.
"""

from .fitted_scene import FittedScene
from .plugin import register_mitsuba_plugin

__all__ = ["FittedScene", "register_mitsuba_plugin"]
