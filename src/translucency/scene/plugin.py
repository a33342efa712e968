r"""The renderer as a Mitsuba plugin: ``<integrator type="translucency">`` in a user's XML.

After :func:`register_mitsuba_plugin` (once Mitsuba runs on a JIT variant, ``llvm_ad_rgb`` or
``cuda_ad_rgb``; ``import translucency`` then ``translucency.register_mitsuba_plugin()``), a scene file
names the renderer like any integrator, and ``mitsuba.render`` prepares the fitted objects on its first
call for a scene (the transports, then the light-in and through-the-body passes) and path-traces the
picture (:mod:`translucency.scene.integrator`).

.. list-table:: Parameters
   :header-rows: 1

   * - name
     - type
     - default
     - meaning
   * - ``models``
     - string
     - (required)
     - ``id=FILE`` pairs separated by commas: the shape with that id is that per-vertex model (its mesh
       from ``translucency export MODEL --ply``, placed by ``to_world``); relative paths as the file's
   * - ``scene_unit_mm``
     - float
     - 1
     - millimetres per scene unit
   * - ``samples``
     - integer
     - 32
     - irradiance samples per vertex of the first pass (a later one: a quarter)
   * - ``passes``
     - integer
     - 2
     - light-in / through-the-body passes
   * - ``max_depth``
     - integer
     - 8
     - longest light path (picture and irradiance)
   * - ``transport``
     - string
     - ``default``
     - the objects' transport (:data:`~translucency.transport.kinds.TRANSPORTS`: ``default``, or
       ``paper`` for the paper's model alone)
   * - ``roughness``
     - float
     - 0
     - GGX α of a dielectric object's boundary

Example (XML)::

    <integrator type="translucency">
        <string name="models" value="pig=pig.model.zip"/>
        <integer name="samples" value="32"/>
    </integrator>

Example (dict)::

    {"type": "translucency", "models": "pig=pig.model.zip", "samples": 32}

Changing an emitter or a shape through ``mi.traverse`` after the first render: call
``integrator.relight()`` (the passes again; the transports are kept).
"""

from __future__ import annotations

from pathlib import Path

from .._validate import TranslucencyError
from ..mitsuba import mitsuba
from ..transport import TransportOptions
from .fitted_scene import FittedScene
from .integrator import integrator_class

#: the plugin's name in a scene file
PLUGIN = "translucency"


def _models(text: str) -> dict:
    mi = mitsuba()
    out = {}
    for item in filter(None, (t.strip() for t in str(text).split(","))):
        key, eq, path = item.partition("=")
        if not eq or not key.strip() or not path.strip():
            raise TranslucencyError(f"integrator translucency: models: expected id=FILE pairs, got {item!r}")
        out[key.strip()] = Path(str(mi.file_resolver().resolve(path.strip())))
    if not out:
        raise TranslucencyError("integrator translucency: models: name at least one id=FILE")
    return out


def register_mitsuba_plugin() -> None:
    """Register ``<integrator type="translucency">`` with Mitsuba (module docstring).

    Loading the integrator only reads its parameters (the model files are opened on the first
    render); a malformed ``models`` is refused when the scene is loaded.

    Examples
    --------
    >>> from translucency import register_mitsuba_plugin
    >>> from translucency.mitsuba import mitsuba
    >>> mi = mitsuba()
    >>> register_mitsuba_plugin()
    >>> import translucency as tl
    >>> model = tl.data.example_path("spot_coarse.model.zip")   # the shape id "object" is fitted by it
    >>> integrator = mi.load_dict({"type": "translucency", "models": f"object={model}", "samples": 8})
    >>> integrator.models == {"object": model}, integrator.options["samples"]
    (True, 8)
    >>> integrator.options["scene_unit_mm"]
    1.0
    >>> try:
    ...     mi.load_dict({"type": "translucency", "models": "pig"})
    ... except RuntimeError as exc:  # Mitsuba wraps the plugin's error; its last line is ours
    ...     print(str(exc).splitlines()[-1])
    TranslucencyError: integrator translucency: models: expected id=FILE pairs, got 'pig'
    """
    mi = mitsuba()
    base = integrator_class()

    class Translucency(base):
        """Mitsuba's side of :class:`~translucency.scene.FittedScene` (module docstring)."""

        def __init__(self, props):
            super().__init__(props)
            get = lambda name, default: props[name] if name in props else default  # noqa: E731
            self.models = _models(get("models", ""))
            self.options = {
                "scene_unit_mm": float(get("scene_unit_mm", 1.0)),
                "samples": int(get("samples", 32)),
                "passes": int(get("passes", 2)),
                "max_depth": int(get("max_depth", 8)),
                "roughness": float(get("roughness", 0.0)),
                "transport": TransportOptions(kind=str(get("transport", "default"))),
            }
            self.fitted = None

        def relight(self) -> None:
            """The passes again (after an emitter or a shape changed)."""
            self.fitted.light()

        def render(self, scene, sensor=0, seed=0, spp=0, develop=True, evaluate=True):
            if self.fitted is None or self.fitted.scene is not scene:
                self.fitted = FittedScene(scene, self.models, **self.options)
                self.fitted.prepare()
                self.fitted.light(seed=int(seed))
                self.glow = self.fitted.glow
            return super().render(scene, sensor, seed, spp, develop, evaluate)

    mi.register_integrator(PLUGIN, lambda props: Translucency(props))
