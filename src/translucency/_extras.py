"""The optional parts of translucency (its *extras*): the package each one needs, and one line where it is
missing.

The core install runs the main job (``translucency demo``), the acquisitions, fits, evaluations and
renders in this process's threads.  The rest is one ``pip install "translucency[NAME]"`` away:

=========  ==========================  ====================================================================
extra      package (module)            what needs it
=========  ==========================  ====================================================================
rig        opencv-python-headless      a rig's photographs: calibration, chessboards, camera projection
           (``cv2``)                   (``import images``, ``import object``, ``acquire *photographs``)
cluster    dask[distributed]           ``--scheduler local:N`` and ``tcp://HOST:PORT`` (work on a cluster)
           (``distributed``)
viewer     fast-simplification         ``view`` of an object: the reduced mesh drawn while the light moves
           (``fast_simplification``)
flip       flip-evaluator              FLIP beside the relative RMSE wherever a picture meets its reference;
           (``flip_evaluator``)        without it the comparison goes on with the RMSE and says so
all        all of the above
=========  ==========================  ====================================================================

A feature that cannot work without its extra raises :class:`MissingExtra` (a
:class:`~translucency.TranslucencyError`: the command line prints it as one ``error:`` line, exit status 2)
naming the command that needs it when a command runs, else the feature; a feature that is optional in a job
(FLIP in the main job's report) asks :func:`optional` and says what it skipped with :func:`skipped`.
"""

from __future__ import annotations

import importlib
import sys
from types import ModuleType

from ._validate import TranslucencyError

#: extra → (its package on PyPI, the module imported, what needs it when no command runs)
EXTRAS = {
    "rig": ("opencv-python-headless", "cv2", "a rig's camera calibration (OpenCV)"),
    "cluster": ("dask[distributed]", "distributed", "a Dask scheduler"),
    "viewer": ("fast-simplification", "fast_simplification", "the viewer's reduced mesh"),
    "flip": ("flip-evaluator", "flip_evaluator", "FLIP (NVIDIA's perceptual difference)"),
}


class MissingExtra(TranslucencyError):
    """A feature needs an extra that is not installed; ``extra`` names it.

    Examples
    --------
    >>> exc = MissingExtra("viewer", "the viewer's reduced mesh")
    >>> exc.extra, str(exc)
    ('viewer', 'the viewer\\'s reduced mesh needs the viewer extra: pip install "translucency[viewer]"')
    """

    def __init__(self, extra: str, who: str):
        self.extra = extra
        super().__init__(f"{who} needs the {extra} extra: {install_line(extra)}")


def install_line(extra: str) -> str:
    """The one command that installs ``extra``.

    Examples
    --------
    >>> install_line("rig")
    'pip install "translucency[rig]"'
    """
    if extra not in EXTRAS and extra != "all":
        raise ValueError(f"no extra {extra!r}; the extras are {', '.join(EXTRAS)}, all")
    return f'pip install "translucency[{extra}]"'


def optional(extra: str) -> ModuleType | None:
    """The module of ``extra`` (:data:`EXTRAS`), imported; None where the extra is not installed.

    Examples
    --------
    >>> optional("flip").__name__   # installed here
    'flip_evaluator'
    """
    module = EXTRAS[extra][1]
    try:
        return importlib.import_module(module)
    except ImportError:
        return None


def require(extra: str, *, what: str | None = None) -> ModuleType:
    """The module of ``extra`` (:data:`EXTRAS`), imported; :class:`MissingExtra` where it is not installed.

    The line names the command that runs (``translucency view needs the viewer extra: pip install
    "translucency[viewer]"``), or, called from Python, ``what`` needs it (default: the extra's feature).
    ``what`` may name the argument that asks for the extra (``scheduler='local:2'``): the command line
    prints it as its flag.

    Examples
    --------
    >>> require("rig").__name__
    'cv2'
    """
    found = optional(extra)
    if found is None:
        command = _command()
        who = what or EXTRAS[extra][2]
        raise MissingExtra(extra, f"{command} with {what}" if command and what else command or who)
    return found


def skipped(extra: str, what: str) -> str:
    """The information line of a job that goes on without ``extra``: ``what`` it skips and the install line.

    Examples
    --------
    >>> skipped("flip", "FLIP in the report")
    'FLIP in the report skipped: it needs the flip extra: pip install "translucency[flip]"'
    """
    return f"{what} skipped: it needs the {extra} extra: {install_line(extra)}"


def _command() -> str | None:
    """The command that runs (``translucency import images``), or None: Click's current context, where the
    command line (the only user of Click here, Typer's own copy or the package) has loaded it; the library
    itself never imports Click."""
    context = None
    for name in ("typer._click.globals", "click.globals"):
        click = sys.modules.get(name)
        context = context or (click.get_current_context(silent=True) if click is not None else None)
    names = []
    while context is not None:
        names.append(context.info_name)
        context = context.parent
    # the root's own name (``translucency``, ``python -m translucency``) is always said as translucency
    return " ".join(["translucency", *reversed(names[:-1])]) if names else None
