"""The library runs every stage: one function per thing a user does, the same for Python and the command
line.

Each function checks its arguments at the boundary (a mistake is one
:class:`~translucency.TranslucencyError` line naming the Python argument), estimates its memory and time
before any work (:mod:`.run`), claims its outputs (never replacing what translucency did not write),
works under a :class:`~.run.Reporter` (silent by default; the command line draws progress bars) and
returns what it made with the summary the command prints.

==================  =============================================================  ===========================
module              functions                                                      command
==================  =============================================================  ===========================
:mod:`.datasets`    :func:`open_dataset`                                           ``info DATA``
:mod:`.inspecting`  :func:`describe`, :func:`describe_materials`                   ``info``, ``materials``
:mod:`.acquiring`   :func:`acquire_planar`, :func:`acquire_mesh`                   ``acquire planar|mesh``
:mod:`.photographing` :func:`acquire_photographs`,                                 ``acquire photographs``,
                    :func:`acquire_object_photographs`                             ``… object-photographs``
:mod:`.importing`   :func:`import_images`, :func:`import_object`                   ``import images|object``
:mod:`.fitting`     :func:`fit_model`                                              ``fit``
:mod:`.evaluating`  :func:`evaluate_report`, :func:`evaluate_model`                ``evaluate``
:mod:`.rendering`   :func:`render_model`                                           ``render``
:mod:`.scene_rendering` :func:`render_scene`                                       ``render scene``
:mod:`.exporting`   :func:`export_model`, :func:`export_ply`, :func:`export_gltf`  ``export``
:mod:`.viewing`     :func:`view_model`                                             ``view``
:mod:`.demo`        :func:`run_demo` (the main job, :mod:`translucency.pipeline`)   ``demo``
:mod:`.examples`    :func:`copy_examples` (the documentation's files)               ``examples``
==================  =============================================================  ===========================

The modules load on
first use of one of their names (the stages load Dask, Matplotlib and Mitsuba's wrappers), so that
:mod:`.run` stays cheap for the command line's start-up.  Units: mm, R_d in mm⁻², linear RGB.
"""

import importlib

from ..acquire.names import (
    GENERATORS as GENERATORS,
)  # cheap (plain names): the command line's --help lists them

#: public name → the module of this package that defines it (loaded on first use)
_HOMES = {
    "open_dataset": "datasets",
    "acquire_planar": "acquiring",
    "acquire_mesh": "acquiring",
    "make_sample": "acquiring",
    "acquire_photographs": "photographing",
    "acquire_object_photographs": "photographing",
    "Photographs": "photographing",
    "import_images": "importing",
    "import_object": "importing",
    "Fitting": "fitting",
    "fit_model": "fitting",
    "evaluate_model": "evaluating",
    "evaluate_report": "evaluating",
    "Evaluation": "evaluating",
    "Rendering": "rendering",
    "SceneRendering": "scene_rendering",
    "render_model": "rendering",
    "render_scene": "scene_rendering",
    "describe": "inspecting",
    "describe_materials": "inspecting",
    "export_model": "exporting",
    "export_ply": "exporting",
    "export_gltf": "exporting",
    "view_model": "viewing",
    "run_demo": "demo",
    "copy_examples": "examples",
    "Reporter": "run",
    "Run": "run",
}

__all__ = sorted([*_HOMES, "GENERATORS"])


def __getattr__(name: str):
    if name not in _HOMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_HOMES[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted({*__all__, *(k for k in globals() if not k.startswith("_"))})
