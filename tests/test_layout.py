"""The rules of the layout (docs/architecture.md, "Rules of the layout"), read from the syntax tree.

Each check walks the source of ``src/translucency`` without importing it and returns every offender as
``translucency/<file>:<line>: <what>``.  The tests run each check on the package itself, and each once on a
small synthetic tree with one violation (the check must report it, and only it) and once on a clean tree
(it must report nothing), so that every kind of violation is shown to be caught.

The units of the layout: a *package* is a folder of ``src/translucency``; the modules at its root form
one more.  Where an import may point (:data:`MAY_IMPORT`): down the pipeline (model → acquire → fit →
evaluate → render) or sideways into the shared homes; the commands (``cli``) and the main job
(``pipeline``) sit on top, and nothing imports the package's façade (``translucency/__init__.py``).
"""

from __future__ import annotations

import ast
import functools
import io
import re
import textwrap
import tokenize
from dataclasses import dataclass
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "translucency"

#: the package root's private modules, shared by design by every package
ROOT_SHARED = frozenset({"_validate", "_version", "_plotting", "_extras"})

#: the shared homes (sideways imports): one concern used by several stages
SHARED = frozenset(
    {"model", "geometry", "angles", "cluster", "mitsuba", "io", "data", "resources", "solvers"}
)

_BASE = ROOT_SHARED | SHARED
#: unit → the units it may import (its own always).  A unit is a folder of src/translucency, or a module
#: of its root by its name (``_resources``/``resources`` → "resources"; ``__init__`` → "translucency",
#: the façade)
MAY_IMPORT: dict[str, frozenset[str]] = {
    **{unit: ROOT_SHARED for unit in ROOT_SHARED},
    **{unit: _BASE for unit in SHARED},
    # the pipeline: an earlier stage never imports a later one
    "acquire": _BASE,
    # the object as a medium, estimated from the scan and walked (its walk is acquire's photon walk): read
    # by the fit that stores it and by the transport that walks the light crossing the body
    "medium": _BASE | {"acquire"},
    "fit": _BASE | {"acquire", "medium"},
    "evaluate": _BASE | {"acquire", "medium", "fit"},
    # a fitted object's light transport, prepared once and drawn by every renderer: on the model alone
    "transport": _BASE | {"medium"},
    "render": _BASE | {"acquire", "medium", "fit", "evaluate", "transport"},
    # a user's Mitsuba scene with fitted objects in it: the prepared objects' transport inside a scene
    "scene": _BASE | {"acquire", "medium", "fit", "evaluate", "transport", "render"},
    # looking at a fitted model: the page and the live viewer, on the prepared object's transport and transfer
    "view": _BASE | {"acquire", "medium", "fit", "evaluate", "transport", "render"},
    # experiments kept for a benchmark or an ablation (unstable): beside the renderers, imported by none
    "experimental": _BASE | {"acquire", "medium", "fit", "evaluate", "transport", "render", "scene"},
    # a real rig: photographs → a data set as acquire writes it (acquire's place in the pipeline); its
    # near peak walks photons on the scan with acquire's own mesh walk (the same stage, sideways)
    "rig": _BASE | {"acquire"},
    # cross-checks beside the pipeline (tests, benchmarks)
    "validate": _BASE | {"acquire", "medium", "fit", "evaluate", "transport", "render"},
    # on top: the workflow as functions (``translucency.fit(...)``), the main job, the commands,
    # ``python -m translucency`` and the façade
    "workflow": _BASE
    | {"acquire", "medium", "fit", "evaluate", "transport", "render", "scene", "rig", "view", "pipeline"},
    "pipeline": _BASE
    | {"acquire", "medium", "fit", "evaluate", "transport", "render", "scene", "rig", "view", "validate"},
    "cli": _BASE
    | {
        "acquire",
        "medium",
        "fit",
        "evaluate",
        "transport",
        "render",
        "scene",
        "rig",
        "view",
        "validate",
        "workflow",
        "pipeline",
    },
    "__main__": frozenset({"cli"}),
    "translucency": _BASE
    | {
        "acquire",
        "medium",
        "fit",
        "evaluate",
        "transport",
        "render",
        "scene",
        "rig",
        "view",
        "validate",
        "workflow",
        "pipeline",
    },
}

#: Mitsuba's calls that build a scene (or a part of one) from a description
SCENE_LOADERS = frozenset({"load_dict", "load_file", "load_string"})

#: comments that are tool directives, not reasons
_DIRECTIVE = re.compile(r"^\s*(noqa\b|type:|pragma\b|fmt:|isort:)")


# ---------------------------------------------------------------------------------------------------------
# The source tree as syntax: modules, their imports, their comments


@dataclass(frozen=True)
class Module:
    """One ``.py`` file of the tree: its dotted name, package, unit, syntax tree and comments."""

    path: Path
    shown: str  # translucency/<file>, as offenders name it
    name: str  # translucency.fit._alternation
    is_package: bool  # an __init__.py
    package: str  # the folder under src/translucency ("" for the root's modules)
    unit: str  # see MAY_IMPORT
    tree: ast.Module
    lines: tuple[str, ...]
    comments: dict[int, str]  # line → comment text (without "#")

    def at(self, node: ast.AST, what: str) -> str:
        return f"{self.shown}:{node.lineno}: {what}"


@dataclass(frozen=True)
class Import:
    """One imported thing: ``target`` a module of the tree (or an outside one), ``name`` a name in it."""

    node: ast.Import | ast.ImportFrom
    alias: ast.alias
    target: str  # dotted module
    name: str | None  # an imported name that is not a module, or None


def _unit(rel: Path) -> str:
    name = rel.parts[0] if len(rel.parts) > 1 else rel.stem
    if name == "__init__":
        return "translucency"
    return "resources" if name in ("_resources", "resources") else name


def _comments(source: str) -> dict[int, str]:
    found = {}
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT:
            found[tok.start[0]] = tok.string.lstrip("#").strip()
    return found


@functools.cache
def modules(root: Path) -> tuple[Module, ...]:
    """Every module under ``root`` (a folder named ``translucency``), parsed."""
    found = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root)
        parts = rel.with_suffix("").parts
        is_package = parts[-1] == "__init__"
        dotted = ".".join((root.name, *(parts[:-1] if is_package else parts)))
        source = path.read_text(encoding="utf-8")
        found.append(
            Module(
                path=path,
                shown=f"{root.name}/{rel.as_posix()}",
                name=dotted,
                is_package=is_package,
                package=rel.parts[0] if len(rel.parts) > 1 else "",
                unit=_unit(rel),
                tree=ast.parse(source, filename=str(path)),
                lines=tuple(source.splitlines()),
                comments=_comments(source),
            )
        )
    return tuple(found)


@functools.cache
def _by_name(root: Path) -> dict[str, Module]:
    return {m.name: m for m in modules(root)}


def _parents(tree: ast.AST) -> dict[ast.AST, ast.AST]:
    return {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}


def _in_def(node: ast.AST, parents: dict) -> bool:
    while node in parents:
        node = parents[node]
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
            return True
    return False


def imports(module: Module, root: Path) -> list[Import]:
    """Every import of ``module``, relative ones resolved, ``from pkg import submodule`` as the submodule."""
    known = _by_name(root)
    found = []
    for node in ast.walk(module.tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                found.append(Import(node, alias, alias.name, None))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.name.split(".") if module.is_package else module.name.split(".")[:-1]
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                if sub in known:
                    found.append(Import(node, alias, sub, None))
                else:
                    found.append(Import(node, alias, target, alias.name))
    return found


def _own(target: str, root: Path) -> Module | None:
    """The module of the tree that ``target`` names (``import a.b.c``: the longest prefix that is one)."""
    known = _by_name(root)
    parts = target.split(".")
    for n in range(len(parts), 0, -1):
        if ".".join(parts[:n]) in known:
            return known[".".join(parts[:n])]
    return None


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _private_module(module: Module) -> bool:
    """A ``_module`` (or a module inside a ``_package``), other than the root's shared ones."""
    parts = module.name.split(".")[1:]
    if len(parts) == 1 and parts[0] in ROOT_SHARED:
        return False
    return any(_private(p) for p in parts)


# ---------------------------------------------------------------------------------------------------------
# The checks: each returns every offender as "file:line: what"


def private_across_packages(root: Path) -> list[str]:
    """No private name (``_x``) or private module (``_mod``) used from another package.

    Relative and absolute imports, ``import a._b``, and ``alias._x`` on a module imported from another
    package; the root's ``_validate``, ``_version``, ``_plotting`` are shared by design.
    """
    offenders = []
    for module in modules(root):
        aliases = {}  # local name → an imported module of another package
        for imp in imports(module, root):
            target = _own(imp.target, root)
            if target is None or target.package == module.package:
                continue
            if _private_module(target):
                offenders.append(module.at(imp.node, f"imports the private module {target.name}"))
            elif imp.name is not None and _private(imp.name):
                what = f"imports the private name {imp.name} from {target.name}"
                offenders.append(module.at(imp.node, what))
            if imp.name is None and (isinstance(imp.node, ast.ImportFrom) or imp.alias.asname):
                aliases[imp.alias.asname or imp.alias.name] = target
        for node in ast.walk(module.tree):
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Name)
                and node.value.id in aliases
                and _private(node.attr)
            ):
                what = f"uses the private name {node.attr} of {aliases[node.value.id].name}"
                offenders.append(module.at(node, what))
    return offenders


def private_modules_export_plain_names(root: Path) -> list[str]:
    """A private module exports plain names to its own package: no ``from ._mod import _x``."""
    offenders = []
    for module in modules(root):
        for imp in imports(module, root):
            target = _own(imp.target, root)
            if target is None or target.package != module.package or not _private_module(target):
                continue
            if imp.name is not None and _private(imp.name) and target.name == imp.target:
                offenders.append(module.at(imp.node, f"imports the private name {imp.name} of {target.name}"))
    return offenders


def scenes_outside_mitsuba(root: Path) -> list[str]:
    """Every Mitsuba scene is built in ``mitsuba/``: ``load_dict`` (``load_file``, ``load_string``) is
    called nowhere else, except on a light's own ``emitter_dict()`` (the documented exception)."""
    offenders = []
    for module in modules(root):
        if module.package == "mitsuba":
            continue
        for node in ast.walk(module.tree):
            if not isinstance(node, ast.Call):
                continue
            func = node.func
            called = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", None)
            if called not in SCENE_LOADERS:
                continue
            arg = node.args[0] if len(node.args) == 1 and not node.keywords else None
            if (
                isinstance(arg, ast.Call)
                and isinstance(arg.func, ast.Attribute)
                and arg.func.attr == "emitter_dict"
            ):
                continue
            offenders.append(module.at(node, f"builds a Mitsuba scene ({called}) outside mitsuba/"))
    return offenders


def _statement_lists(tree: ast.AST):
    for node in ast.walk(tree):
        for field in ("body", "orelse", "finalbody"):
            body = getattr(node, field, None)
            if isinstance(body, list) and body and isinstance(body[0], ast.stmt):
                yield body


def _a_reason(comment: str | None) -> bool:
    return bool(comment) and not _DIRECTIVE.match(comment) and re.search(r"\w", comment) is not None


def local_imports_without_reason(root: Path) -> list[str]:
    """Every import inside a def carries its reason in a comment: on its own line(s), or on the line above.

    A run of imports one after the other (blank lines between allowed, as isort groups them) shares one
    reason; the line above counts when it is a comment, or a block's header (``try:  # reason``).
    """
    offenders = []
    for module in modules(root):
        parents = _parents(module.tree)
        for body in _statement_lists(module.tree):
            runs, run = [], []
            for stmt in body:
                if isinstance(stmt, ast.Import | ast.ImportFrom):
                    run.append(stmt)
                elif run:
                    runs.append(run)
                    run = []
            if run:
                runs.append(run)
            for run in runs:
                if not _in_def(run[0], parents):
                    continue
                lines = set(range(run[0].lineno, run[-1].end_lineno + 1))
                above = run[0].lineno - 1
                text = module.lines[above - 1].strip() if above >= 1 else ""
                code = text.split("#", 1)[0].strip()
                if text.startswith("#") or code.endswith(":"):
                    lines.add(above)
                if not any(_a_reason(module.comments.get(line)) for line in lines):
                    names = ", ".join(alias.name for stmt in run for alias in stmt.names)
                    what = f"function-local import of {names} without its reason in a comment"
                    offenders.append(module.at(run[0], what))
    return offenders


def imports_against_the_pipeline(root: Path) -> list[str]:
    """Imports point down the pipeline or sideways into a shared home (:data:`MAY_IMPORT`); nothing
    imports the façade (``translucency/__init__.py``); every unit has its place in the table."""
    offenders = []
    for module in modules(root):
        allowed = MAY_IMPORT.get(module.unit)
        if allowed is None:
            offenders.append(
                f"{module.shown}:1: the unit {module.unit!r} has no place in the layout "
                "(MAY_IMPORT in tests/test_layout.py, docs/architecture.md)"
            )
            continue
        for imp in imports(module, root):
            target = _own(imp.target, root)
            if target is None or target.unit == module.unit:
                continue
            if target.unit == "translucency":
                what = "imports the package's façade; import from the module that defines it"
                offenders.append(module.at(imp.node, what))
            elif target.unit in MAY_IMPORT and target.unit not in allowed:
                offenders.append(module.at(imp.node, f"{module.unit} imports {target.unit} ({target.name})"))
    return offenders


def engines_outside_their_homes(root: Path) -> list[str]:
    """Mitsuba and Dr.Jit are loaded only by ``translucency.mitsuba`` (the libLLVM path is set first),
    pyplot only by ``translucency._plotting.pyplot()`` (the Agg backend is chosen first)."""
    offenders = []
    for module in modules(root):
        for imp in imports(module, root):
            top = imp.target.split(".")[0]
            full = imp.target if imp.name is None else f"{imp.target}.{imp.name}"
            if top in ("mitsuba", "drjit") and module.package != "mitsuba":
                offenders.append(module.at(imp.node, f"imports {top} itself (use translucency.mitsuba)"))
            elif full in ("matplotlib.pyplot", "pylab") and module.name != f"{root.name}._plotting":
                offenders.append(module.at(imp.node, f"imports {full} (use translucency._plotting.pyplot)"))
    return offenders


def stated_more_than_once(root: Path) -> list[str]:
    """The spot's falloff ``SPOT_BEAM_FRACTION`` is stated in ``mitsuba/`` only; the atomic replace of a
    written file (``os.replace``, ``os.rename``, ``shutil.move``) happens in ``io/`` only."""
    offenders = []
    for module in modules(root):
        for node in ast.walk(module.tree):
            if isinstance(node, ast.Assign | ast.AnnAssign) and module.package != "mitsuba":
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                if any(isinstance(t, ast.Name) and t.id == "SPOT_BEAM_FRACTION" for t in targets):
                    offenders.append(module.at(node, "states SPOT_BEAM_FRACTION outside mitsuba/"))
            if isinstance(node, ast.Call) and module.package != "io" and isinstance(node.func, ast.Attribute):
                owner = node.func.value
                call = f"{getattr(owner, 'id', '?')}.{node.func.attr}"
                if call in ("os.replace", "os.rename", "shutil.move"):
                    offenders.append(module.at(node, f"moves a written file ({call}) outside io/"))
    return offenders


def lights_told_apart_outside_lights(root: Path) -> list[str]:
    """No ``isinstance`` (``issubclass``) on a light class outside ``render/lights/``: the rest of the
    package asks a light through its protocol (``render.lights.Light``), so that a new kind of light is one
    class there.

    A light class: a class of ``render/lights`` (a module, or a package and its modules) whose name ends
    in ``Light``, named plainly or as an attribute (``lights.PointLight``), alone or in a tuple.
    """
    home = f"{root.name}.render.lights"
    homes = [m for m in modules(root) if m.name == home or m.name.startswith(home + ".")]
    kinds = {
        node.name
        for module in homes
        for node in module.tree.body
        if isinstance(node, ast.ClassDef) and node.name.endswith("Light")
    }
    offenders = []
    for module in modules(root):
        if module in homes:
            continue
        for node in ast.walk(module.tree):
            if not (
                isinstance(node, ast.Call)
                and getattr(node.func, "id", None) in ("isinstance", "issubclass")
                and len(node.args) == 2
            ):
                continue
            named = {
                n.id if isinstance(n, ast.Name) else n.attr
                for n in ast.walk(node.args[1])
                if isinstance(n, ast.Name | ast.Attribute)
            }
            if named & kinds:
                on = ", ".join(sorted(named & kinds))
                what = f"tells lights apart ({node.func.id} on {on}) outside render/lights"
                offenders.append(module.at(node, what))
    return offenders


#: what a module of ``cli/`` may import from the package: the library's functions (``workflow``), the one
#: error type, the version, and the command line's own modules
CLI_USES = frozenset({"cli", "workflow", "_validate", "_version"})
#: the longest function of ``cli/``, in lines (its options are declared above it, as module constants)
CLI_LONGEST = 60


def commands_only_parse_and_print(root: Path) -> list[str]:
    """The command line only parses and prints: a module of ``cli/`` imports nothing of the package but
    the library's functions (``workflow``), ``_validate``, ``_version`` and ``cli`` itself, and none of its
    functions is longer than :data:`CLI_LONGEST` lines — the stage logic lives in the library, where a
    Python user calls it too."""
    offenders = []
    for module in modules(root):
        if module.unit != "cli":
            continue
        for imp in imports(module, root):
            target = _own(imp.target, root)
            if target is not None and target.unit not in CLI_USES:
                offenders.append(module.at(imp.node, f"a command imports {target.name} (call the library)"))
        for node in ast.walk(module.tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                length = node.end_lineno - node.lineno + 1
                if length > CLI_LONGEST:
                    what = f"the command's function {node.name} is {length} lines (at most {CLI_LONGEST})"
                    offenders.append(module.at(node, what))
    return offenders


CHECKS = (
    private_across_packages,
    private_modules_export_plain_names,
    scenes_outside_mitsuba,
    local_imports_without_reason,
    imports_against_the_pipeline,
    engines_outside_their_homes,
    stated_more_than_once,
    lights_told_apart_outside_lights,
    commands_only_parse_and_print,
)


def assert_none(offenders: list[str], check) -> None:
    summary = " ".join((check.__doc__ or check.__name__).split("\n\n")[0].split())
    assert not offenders, f"{summary}\n{len(offenders)} offender(s):\n  " + "\n  ".join(offenders)


# ---------------------------------------------------------------------------------------------------------
# The package itself


@pytest.mark.parametrize("check", CHECKS, ids=lambda c: c.__name__)
def test_the_package_keeps_the_layout(check):
    assert modules(SRC), f"no modules found under {SRC}"
    assert_none(check(SRC), check)


# ---------------------------------------------------------------------------------------------------------
# Each check catches its kind of violation: a clean synthetic tree passes, one violation fails


CLEAN = {
    "__init__.py": """
        from .fit import fit_all
        from .model.core import Model
        """,
    "__main__.py": "from .cli.app import main\n",
    "_validate.py": "class TranslucencyError(ValueError):\n    pass\n",
    "_version.py": '__version__ = "0"\n',
    "_plotting.py": """
        def pyplot():
            import matplotlib  # heavy, and the backend must be chosen before pyplot loads

            matplotlib.use("Agg")
            # after use("Agg")
            import matplotlib.pyplot as plt

            return plt
        """,
    "_resources.py": "from .io.atomic import move\n",
    "geometry.py": "from ._validate import TranslucencyError\n",
    "pipeline.py": """
        from . import _resources
        from .evaluate.errors import error
        from .render import picture
        """,
    "model/__init__.py": "from .core import Model\n",
    "model/_base.py": "class Base:\n    _hidden = 1\n",
    "model/core.py": """
        from .._validate import TranslucencyError
        from .._version import __version__
        from ._base import Base


        class Model(Base):
            pass
        """,
    "model/pbd.py": "from .core import Model\n\n\nclass _Tabulated(Model):\n    pass\n",
    "model/tables.py": "from .pbd import _Tabulated  # a private name of a public module, same package\n",
    "mitsuba/__init__.py": """
        from ._engine import drjit, mitsuba
        from .scenes import SPOT_BEAM_FRACTION, build
        """,
    "mitsuba/_engine.py": """
        def mitsuba():
            try:  # imported here: the libLLVM path must be set first
                import drjit
                import mitsuba as mi
            except ImportError:
                raise
            return mi, drjit


        def drjit():
            import drjit as dr  # after mitsuba()

            return dr
        """,
    "mitsuba/scenes.py": """
        from ._engine import mitsuba

        SPOT_BEAM_FRACTION = 0.75


        def build(d):
            return mitsuba().load_dict(d)
        """,
    "io/__init__.py": "",
    "io/atomic.py": "import os\n\n\ndef move(a, b):\n    os.replace(a, b)\n",
    "acquire/__init__.py": "from .walk import walk\n",
    "acquire/walk.py": """
        from ..geometry import TranslucencyError
        from ..mitsuba import SPOT_BEAM_FRACTION, mitsuba
        from ..model import Model


        def walk(light):
            emitter = mitsuba().load_dict(light.emitter_dict())
            # the walk's clock: only the probe is timed
            import time

            return emitter, time, Model, SPOT_BEAM_FRACTION
        """,
    "fit/__init__.py": "from ._core import fit_all\n",
    "fit/_core.py": """
        from ..acquire import walk
        from ..model.core import Model


        def fit_all():
            return Model(), walk
        """,
    "fit/planar.py": "from ._core import fit_all\n",
    "evaluate/__init__.py": "",
    "evaluate/errors.py": """
        from .._plotting import pyplot
        from ..fit import fit_all


        def error():
            plt = pyplot()
            from matplotlib.colors import LogNorm  # matplotlib is loaded by pyplot() above

            return plt, LogNorm, fit_all
        """,
    "render/__init__.py": "from .picture import picture\n",
    "render/camera.py": """
        def aim(target):
            return target if isinstance(target, tuple) else tuple(target)
        """,
    "render/lights.py": """
        class Light:
            delta = False


        class PointLight(Light):
            delta = True


        def place(light, placement):
            return light if isinstance(light, PointLight) else placement
        """,
    "render/picture.py": """
        import matplotlib.image as mpimg

        from ..acquire.walk import walk
        from ..evaluate import errors
        from ..io.atomic import move


        def picture():
            return mpimg, walk, errors.error, move
        """,
    "rig/__init__.py": "",
    "rig/importer.py": "from ..io.atomic import move\nfrom ..mitsuba import mitsuba\n",
    "validate/__init__.py": "",
    "validate/volpath.py": "from ..acquire.walk import walk\nfrom ..render.picture import picture\n",
    "cli/__init__.py": "",
    "cli/app.py": """
        import typer

        from .._validate import TranslucencyError
        from ..workflow.fitting import fit_model


        def main():
            return typer, TranslucencyError, fit_model
        """,
    "workflow/__init__.py": "",
    "workflow/fitting.py": """
        from ..fit import fit_all
        from ..render.picture import picture
        from ..rig import importer


        def fit_model():
            return fit_all(), importer, picture
        """,
    "data/__init__.py": "DATA_DIR = None\n",
}

#: (check, {file: its new source}, where the one offender is)
VIOLATIONS = [
    # (a) private names and modules across packages
    (private_across_packages, {"rig/fitting.py": "from ..fit._core import fit_all\n"}, "rig/fitting.py:1"),
    (private_across_packages, {"rig/fitting.py": "import translucency.fit._core\n"}, "rig/fitting.py:1"),
    (private_across_packages, {"render/x.py": "X = 1\nfrom ..acquire.walk import _step\n"}, "render/x.py:2"),
    (private_across_packages, {"render/x.py": "from translucency.model import _base\n"}, "render/x.py:1"),
    (private_across_packages, {"__init__.py": "from .mitsuba._engine import drjit\n"}, "__init__.py:1"),
    (
        private_across_packages,
        {"_resources.py": "def f():\n    from .fit._core import x  # why\n"},
        "_resources.py:2",
    ),
    (private_across_packages, {"cli/x.py": "from .. import _resources\n"}, "cli/x.py:1"),
    (private_across_packages, {"cli/x.py": "from .. import fit\n\nfit._core.fit_all()\n"}, "cli/x.py:3"),
    (
        private_modules_export_plain_names,
        {"fit/planar.py": "from ._core import _helper\n"},
        "fit/planar.py:1",
    ),
    # (b) Mitsuba scenes only in mitsuba/
    (
        scenes_outside_mitsuba,
        {"validate/beam.py": "def render(mi, scene):\n    return mi.load_dict(scene)\n"},
        "validate/beam.py:2",
    ),
    (
        scenes_outside_mitsuba,
        {"rig/photo.py": "from ..mitsuba import mitsuba\n\nS = mitsuba().load_dict({'type': 'scene'})\n"},
        "rig/photo.py:3",
    ),
    # (c) every function-local import carries its reason
    (
        local_imports_without_reason,
        {"acquire/probe.py": "def probe():\n    import time\n"},
        "acquire/probe.py:2",
    ),
    (
        local_imports_without_reason,
        {"cli/rig.py": "def cmd():\n    x = 1  # mm\n    from ..rig import importer\n"},
        "cli/rig.py:3",
    ),
    (
        local_imports_without_reason,
        {"io/x.py": "def f():\n    import json  # noqa: F401\n"},
        "io/x.py:2",
    ),
    (
        local_imports_without_reason,
        {"io/x.py": "class A:\n    def f(self):\n        # why\n        x = 1\n        import json\n"},
        "io/x.py:5",
    ),
    # (d) the direction of imports, the engines' homes, things stated once
    (imports_against_the_pipeline, {"acquire/x.py": "from ..fit import fit_all\n"}, "acquire/x.py:1"),
    (imports_against_the_pipeline, {"acquire/x.py": "from ..render import picture\n"}, "acquire/x.py:1"),
    (imports_against_the_pipeline, {"model/x.py": "from ..acquire import walk\n"}, "model/x.py:1"),
    (
        imports_against_the_pipeline,
        {"_resources.py": "def f():\n    from .fit import x  # why\n"},
        "_resources.py:2",
    ),
    (imports_against_the_pipeline, {"rig/x.py": "from ..fit import fit_all\n"}, "rig/x.py:1"),
    (imports_against_the_pipeline, {"render/x.py": "from ..cli.app import main\n"}, "render/x.py:1"),
    (imports_against_the_pipeline, {"pipeline.py": "from .cli import app\n"}, "pipeline.py:1"),
    (imports_against_the_pipeline, {"pipeline.py": "from .workflow import run\n"}, "pipeline.py:1"),
    (imports_against_the_pipeline, {"fit/x.py": "from translucency import Model\n"}, "fit/x.py:1"),
    (imports_against_the_pipeline, {"newthing.py": "X = 1\n"}, "newthing.py:1"),
    (
        engines_outside_their_homes,
        {"validate/x.py": "def f():\n    import drjit as dr  # why\n"},
        "validate/x.py:2",
    ),
    (engines_outside_their_homes, {"render/x.py": "from mitsuba import load_dict\n"}, "render/x.py:1"),
    (engines_outside_their_homes, {"evaluate/x.py": "import matplotlib.pyplot as plt\n"}, "evaluate/x.py:1"),
    (engines_outside_their_homes, {"evaluate/x.py": "from matplotlib import pyplot\n"}, "evaluate/x.py:1"),
    (stated_more_than_once, {"render/lights.py": "SPOT_BEAM_FRACTION = 0.75\n"}, "render/lights.py:1"),
    # (f) the command line parses, calls the library and prints
    (commands_only_parse_and_print, {"cli/x.py": "from ..fit import fit_all\n"}, "cli/x.py:1"),
    (commands_only_parse_and_print, {"cli/x.py": "from ..io.atomic import move\n"}, "cli/x.py:1"),
    (
        commands_only_parse_and_print,
        {"cli/x.py": "def cmd():\n" + "    x = 1\n" * CLI_LONGEST},
        "cli/x.py:1",
    ),
    (
        stated_more_than_once,
        {"render/x.py": "import os\n\n\ndef save(a, b):\n    os.replace(a, b)\n"},
        "render/x.py:5",
    ),
    # (e) lights answer through their protocol: no isinstance on a light class outside render/lights.py
    (
        lights_told_apart_outside_lights,
        {"render/x.py": "from .lights import PointLight\n\nA = isinstance(1, PointLight)\n"},
        "render/x.py:3",
    ),
    (
        lights_told_apart_outside_lights,
        {"view/x.py": "from ..render import lights\n\nB = issubclass(int, (str, lights.Light))\n"},
        "view/x.py:3",
    ),
]


def _tree(tmp_path: Path, files: dict[str, str]) -> Path:
    root = tmp_path / "translucency"
    for rel, source in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(source).lstrip("\n"))
    return root


@pytest.mark.parametrize("check", CHECKS, ids=lambda c: c.__name__)
def test_a_clean_tree_passes(check, tmp_path):
    assert_none(check(_tree(tmp_path, CLEAN)), check)


@pytest.mark.parametrize(
    ("check", "change", "where"), VIOLATIONS, ids=[f"{c.__name__}-{w}" for c, _, w in VIOLATIONS]
)
def test_one_violation_fails(check, change, where, tmp_path):
    root = _tree(tmp_path, {**CLEAN, **change})
    offenders = check(root)
    assert [o.split(": ", 1)[0] for o in offenders] == [f"translucency/{where}"], offenders
    with pytest.raises(AssertionError, match=re.escape(f"translucency/{where}")):
        assert_none(offenders, check)


def test_every_check_is_shown_to_catch_a_violation():
    assert {check for check, _, _ in VIOLATIONS} == set(CHECKS)
