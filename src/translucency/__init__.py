"""translucency — measure, fit, evaluate and render heterogeneous translucent materials
with the empirical subsurface-scattering model of Fuchs, Goesele, Chen and Seidel.

Pipeline: :mod:`translucency.model` → acquire → fit → evaluate → render, with :mod:`translucency.io`
and :mod:`translucency.cli` beside.  Units: mm, R_d in mm⁻², σ in mm⁻¹, linear RGB.

The workflow as functions (:mod:`translucency.workflow`, loaded on first use)::

    import translucency as tl
    data = tl.data.default_dataset()
    fitting = tl.fit_model(data, "iso")
    print(tl.evaluate_model(fitting.result, data, truth=tl.data.default_truth()).rel_l2)

The functions are verbs with their object (``fit_model``, ``evaluate_model``, ``render_model``); the
stages are the packages (``translucency.fit``, ``translucency.evaluate``, ``translucency.render``): one
name, one meaning.
"""

from ._validate import TranslucencyError
from ._version import __version__
from .mitsuba import prepare_libllvm as _prepare_libllvm

#: the names loaded from their modules when first used, so that ``import translucency`` (and with it every
#: command's ``--help``) stays cheap: Zarr and the model classes load only for those who use them
_LAZY = {
    "data": "data",  # the module itself: the embedded data sets
    "ModelFileError": "io.model_file",
    "load_model": "io.model_file",
    "save_model": "io.model_file",
    "MATERIALS": "model",
    "BurleyModel": "model",
    "DipoleModel": "model",
    "ExponentialModel": "model",
    "PlanarAlpha": "model",
    "VertexAlpha": "model",
    "material": "model",
    "TransportOptions": "transport",  # the transport's choices, one object for every renderer
    "PreparedObject": "transport",  # a fitted object with the transport every renderer draws
    "register_transport": "transport",  # a transport variant drawn by name
    "FittedScene": "scene",  # fitted objects in a user's Mitsuba scene
    "register_mitsuba_plugin": "scene",  # <integrator type="translucency"> in a Mitsuba XML
}

#: the workflow's functions, loaded from :mod:`translucency.workflow` when first used
_WORKFLOW = (
    "acquire_planar",
    "acquire_mesh",
    "open_dataset",
    "fit_model",
    "evaluate_model",
    "evaluate_report",
    "render_model",
    "render_scene",
    "import_images",
    "import_object",
    "acquire_photographs",
    "acquire_object_photographs",
    "make_sample",
    "describe",
    "describe_materials",
    "export_model",
    "export_ply",
    "export_gltf",
    "view_model",
    "run_demo",
    "copy_examples",
    "Fitting",
    "Photographs",
    "Evaluation",
    "Rendering",
    "SceneRendering",
)

__all__ = [
    "TranslucencyError",
    "ModelFileError",
    "load_model",
    "save_model",
    "ExponentialModel",
    "DipoleModel",
    "BurleyModel",
    "PlanarAlpha",
    "VertexAlpha",
    "MATERIALS",
    "material",
    "data",
    "TransportOptions",
    "PreparedObject",
    "register_transport",
    "FittedScene",
    "register_mitsuba_plugin",
    *_WORKFLOW,
    "__version__",
]


def __getattr__(name: str):
    if name in _WORKFLOW:
        from . import workflow  # heavy: the stages load Dask, Matplotlib and Mitsuba's wrappers

        value = getattr(workflow, name)
    elif name in _LAZY:
        import importlib  # only when a lazy name is first used

        module = importlib.import_module(f".{_LAZY[name]}", __name__)
        value = module if _LAZY[name] == name else getattr(module, name)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted({*__all__, *(k for k in globals() if not k.startswith("_"))})


_prepare_libllvm()  # before any import of Mitsuba or Dr.Jit in this process (theirs or ours)
