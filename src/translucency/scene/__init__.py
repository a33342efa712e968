"""Fitted objects in a user's own Mitsuba 3 scene: lit by every emitter, shadowed and lit by every other
shape, lighting them back, seen through the scene's camera.

:mod:`.pose` (where the model's mesh stands) → :mod:`.fitted` (an object: model, transport, boundary) →
:mod:`.surfaces` (the objects as glowing surfaces: evaluated and sampled) → :mod:`.integrator` (the path
tracer) → :mod:`.irradiance` (the light at the vertices) → :mod:`.fitted_scene` (prepare, light, render).
"""

from .fitted_scene import FittedScene

__all__ = ["FittedScene"]
