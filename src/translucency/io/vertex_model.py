"""A per-vertex model: the one loader every reader of an object's model uses, and the one message for a
planar model where a per-vertex model (a fit on a mesh data set, :mod:`translucency.io.mesh_dataset`)
belongs."""

from __future__ import annotations

from pathlib import Path

from .._validate import TranslucencyError
from ..model import ReflectanceModel
from .inputs import expect_input
from .model_file import read_model

__all__ = ["check_vertex_model", "load_vertex_model"]


def load_vertex_model(path, purpose: str) -> tuple[ReflectanceModel, dict]:
    """Read a per-vertex model file (a fit on a mesh data set) and its header, the file opened once.

    ``path`` is refused in one line when it is another of the tool's kinds (a data set, a mesh file:
    :func:`~translucency.io.inputs.expect_input`), read and validated as
    :func:`~translucency.io.load_model` reads it, and refused by :func:`check_vertex_model` when its
    model is planar.

    Parameters
    ----------
    path : str or Path
        A file written by :func:`~translucency.io.save_model`.
    purpose : str
        What needs the per-vertex model, as the message says it: ``"render"``, ``"export"``,
        ``"--compare"``, ``"the scene's object 'ball'"``.

    Returns
    -------
    model : ReflectanceModel
        The model, ``geometry == "mesh"``.
    header : dict
        The file's header (as :func:`~translucency.io.read_header` returns it).

    Raises
    ------
    TranslucencyError
        One line naming the file: its fault (:class:`~translucency.io.ModelFileError`), or that its
        model is planar.

    Examples
    --------
    >>> import tempfile, translucency as tl
    >>> from translucency.io import save_model
    >>> m = tl.ExponentialModel([[0.0, 0.0]], [[[[1.0]]]], [[[[-2.0]]]],
    ...                         tl.PlanarAlpha.uniform((2, 2)), s_g=[1.0], s_b=[1.0])
    >>> p = save_model(m, tempfile.mkdtemp() + "/planar.model.zip")
    >>> try:
    ...     load_vertex_model(p, "render")
    ... except TranslucencyError as exc:
    ...     print(str(exc).split("/")[-1])
    planar.model.zip: a planar model; render needs a per-vertex model (translucency fit on a mesh data set)
    """
    path = Path(path)
    expect_input(path, ("model file",))
    model, header = read_model(path)
    check_vertex_model(model, purpose, path)
    return model, header


def check_vertex_model(model, purpose: str, source="model") -> None:
    """Refuse, in the one line every per-vertex reader says, a ``model`` that is not per-vertex.

    ``purpose``: what needs it (:func:`load_vertex_model`); ``source``: what the message names, the
    file the model was read from or the argument it was given as.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> try:
    ...     check_vertex_model(SimpleNamespace(geometry="planar"), "render")
    ... except TranslucencyError as exc:
    ...     print(exc)
    model: a planar model; render needs a per-vertex model (translucency fit on a mesh data set)
    """
    if getattr(model, "geometry", None) != "mesh":
        raise TranslucencyError(
            f"{source}: a planar model; {purpose} needs a per-vertex model "
            "(translucency fit on a mesh data set)"
        )
