"""translucency — measure, fit, evaluate and render heterogeneous translucent materials
with the empirical subsurface-scattering model of Fuchs, Goesele, Chen and Seidel.

Pipeline: :mod:`translucency.model` → acquire → :mod:`translucency.fit` →
:mod:`translucency.evaluate` → render, with :mod:`translucency.io` and
:mod:`translucency.cli` beside.  Units: mm, R_d in mm⁻², σ in mm⁻¹, linear RGB.
"""

from ._validate import TranslucencyError
from ._version import __version__
from .io.model_file import ModelFileError, load_model, save_model
from .mitsuba._engine import prepare_libllvm
from .model import (
    MATERIALS,
    BurleyModel,
    DipoleModel,
    ExponentialModel,
    PlanarAlpha,
    VertexAlpha,
    material,
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
    "__version__",
]

prepare_libllvm()  # before any import of Mitsuba or Dr.Jit in this process (theirs or ours)
