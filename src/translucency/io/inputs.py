"""What a path given to a command holds, and one line when it is not what the command takes.

A newcomer gives a model where a data set belongs, a mesh file where a data set belongs, the two
arguments of ``evaluate`` swapped: each reader alone would say "not a readable Zarr data set" or "not a
zip archive".  :func:`what_is` recognises the tool's own kinds (:func:`translucency.io.outputs.kind_of`:
data sets, model files, output folders, JSON summaries) and a mesh or volume file by its suffix;
:func:`expect_input` refuses a path of another kind with what it is and what to do with it.
A path that does not exist, or that is none of these kinds, is left to the reader, whose message
names the fault in the file.

Examples
--------
>>> import tempfile
>>> mesh = Path(tempfile.mkdtemp()) / "bunny.obj"
>>> _ = mesh.write_text("v 0 0 0")
>>> try:
...     expect_input(mesh, ("planar data set", "mesh data set"))
... except TranslucencyError as exc:
...     print(str(exc).split(";")[0].split("/")[-1])
bunny.obj: is a mesh file, not a data set
"""

from __future__ import annotations

from pathlib import Path

from .._validate import TranslucencyError
from .outputs import kind_of

#: suffixes of the mesh files :func:`translucency.io.mesh.load_mesh` reads
MESH_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")

#: what each group of kinds is called in a message
_NAMES = {
    ("planar data set", "mesh data set"): "a data set",
    ("planar data set",): "a planar data set",
    ("mesh data set",): "a mesh data set",
    ("model file",): "a model file",
    ("volume file",): "a volume (.npz)",
    ("mesh file",): "a mesh file (OBJ, PLY, STL, ...)",
    ("model file", "planar data set", "mesh data set"): "a model file or a data set",
}

#: the data sets (planar or mesh) a command reads
DATA_SETS = ("planar data set", "mesh data set")


def what_is(path) -> str | None:
    """One of the tool's kinds (``planar data set``, ``mesh data set``, ``model file``, ``output folder``,
    ``json summary``), ``mesh file`` or ``volume file`` by suffix; None for a missing path or anything
    else."""
    path = Path(path)
    if not path.exists():
        return None
    kind = kind_of(path)
    if kind is not None:
        return kind
    if path.is_file() and path.suffix.lower() in MESH_SUFFIXES:
        return "mesh file"
    if path.is_file() and path.suffix.lower() == ".npz":
        return "volume file"
    return None


def _hint(path: Path, what: str, takes: tuple) -> str:
    """What to do with a ``what`` where ``takes`` was expected."""
    if what == "mesh file" and "volume file" in takes:
        return f"a mesh is the object's surface: acquire mesh --mesh {path} (--volume is its filling)"
    if what == "mesh file":
        return f"make a data set of it with: translucency acquire mesh --mesh {path} --out DATA.zarr"
    if what in DATA_SETS:
        return f"fit a model to it with: translucency fit {path} -o MODEL.model.zip"
    if what == "model file":
        return f"give a data set (.zarr); `translucency info {path}` names the one it was fitted to"
    if what == "volume file":
        return "a volume is the filling of --volume (acquire planar|mesh)"
    if what == "output folder":
        return "it is a folder of figures that evaluate or render wrote"
    return "it is a JSON summary that translucency wrote"


def expect_input(path, takes: tuple, option: str | None = None) -> None:
    """Refuse ``path`` in one line (naming ``option``, or the path alone for an argument) when it is a
    recognised kind other than ``takes`` (see the module docstring); otherwise return."""
    if path is None:
        return
    path = Path(path)
    what = what_is(path)
    if what is None or what in takes:
        return
    label = f"{option} {path}" if option else str(path)
    wanted = _NAMES.get(tuple(takes), " or ".join(takes))
    article = "an" if what[0] in "aeiou" else "a"
    raise TranslucencyError(f"{label}: is {article} {what}, not {wanted}; {_hint(path, what, tuple(takes))}")
