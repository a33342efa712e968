"""Outputs a command may write, replace or remove — and the ones it must never touch.

The rule, for every command that writes (acquire, fit, evaluate, render, demo):

* an output that does not exist is created;
* an output that exists is replaced only with ``overwrite`` **and** only when it
  is recognisably the tool's own, of the kind the command writes (a planar or
  mesh data set, a model file, an output folder carrying the marker file
  :data:`MARKER`, a JSON summary that names the tool);
* the current folder, any folder above it, an input of the same command, a
  folder holding an input, and anything inside an input are refused whatever
  the flags;
* removing an old data set removes only the Zarr nodes the tool wrote (the
  ``zarr.json`` files and array folders); anything else found inside is kept.

Every refusal is a :class:`~translucency._validate.TranslucencyError` naming the
argument and the path, and a message recommends ``overwrite=True`` only for the tool's
own outputs (the command line says ``--out`` and ``--overwrite``: :mod:`translucency.cli._flags`).

Examples
--------
>>> import tempfile
>>> folder = Path(tempfile.mkdtemp())
>>> (folder / "thesis.tex").write_text("my thesis")
9
>>> try:
...     claim_output(folder / "thesis.tex", "model file", overwrite=True)
... except TranslucencyError as exc:
...     print(str(exc).split(";")[0])  # doctest: +ELLIPSIS
out /.../thesis.tex: exists and is not a translucency model file
>>> (folder / "thesis.tex").read_text()
'my thesis'
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import tempfile
import warnings
import zipfile
from contextlib import contextmanager
from pathlib import Path

from .._validate import TranslucencyError
from .._version import __version__

#: the marker file of an output folder (render, report, demo); JSON with the tool's name
MARKER = ".translucency-output.json"

#: what each kind of output is called in messages
KINDS = ("planar data set", "mesh data set", "model file", "output folder", "json summary", "mesh file")
#: the line a PLY the tool wrote carries in its header (:func:`kind_of` reads it)
PLY_COMMENT = "comment written_by translucency"

#: the header key of each kind of data set (kept here so that this module imports no stage)
DATASET_KEYS = {"planar data set": "translucency_dataset", "mesh data set": "translucency_mesh_dataset"}
_MODEL_KEY = "translucency_model"
_FOLDER_KINDS = ("planar data set", "mesh data set", "output folder")


def _a(kind: str) -> str:
    """``kind`` with its article: "a model file", "an output folder"."""
    return ("an " if kind[0] in "aeiou" else "a ") + kind


# -- recognising the tool's own outputs -------------------------------------------------------
def _zarr_attributes(meta: bytes) -> dict:
    try:
        node = json.loads(meta)
    except (ValueError, UnicodeDecodeError):
        return {}
    attrs = node.get("attributes") if isinstance(node, dict) else None
    return attrs if isinstance(attrs, dict) else {}


def kind_of(path) -> str | None:
    """Which of the tool's outputs ``path`` is (one of :data:`KINDS`), or None for anything else.

    Reads only metadata: a data set's root ``zarr.json``, a model file's
    ``zarr.json`` inside its zip, an output folder's marker, a JSON file's
    ``written_by`` field, a PLY's header comment (:data:`PLY_COMMENT`), a binary glTF's first scene's
    ``extras["translucency"]["written_by"]`` (:mod:`translucency.io.gltf`).
    """
    path = Path(path)
    try:
        if path.is_dir():
            meta = path / "zarr.json"
            if meta.is_file():
                attrs = _zarr_attributes(meta.read_bytes())
                for kind, key in DATASET_KEYS.items():
                    if isinstance(attrs.get(key), dict):
                        return kind
            marker = path / MARKER
            if marker.is_file() and json.loads(marker.read_text()).get("written_by") == "translucency":
                return "output folder"
            return None
        if path.is_file():
            if zipfile.is_zipfile(path):
                with zipfile.ZipFile(path) as zf:
                    if "zarr.json" in zf.namelist() and _MODEL_KEY in _zarr_attributes(zf.read("zarr.json")):
                        return "model file"
                return None
            if path.suffix == ".ply":
                with open(path, "rb") as f:
                    head = f.read(512)
                return "mesh file" if PLY_COMMENT.encode() in head.split(b"end_header")[0] else None
            if path.suffix.lower() == ".glb":
                return "mesh file" if _glb_written_here(path) else None
            if path.suffix == ".json" and path.stat().st_size < 50_000_000:
                obj = json.loads(path.read_text())
                if isinstance(obj, dict) and str(obj.get("written_by", "")).startswith("translucency"):
                    return "json summary"
    except (OSError, ValueError, zipfile.BadZipFile):
        return None
    return None


def _glb_written_here(path: Path) -> bool:
    """Whether a .glb's JSON chunk (the first, after the 12-byte header) names translucency as its writer."""
    with open(path, "rb") as f:
        head = f.read(20)
        if len(head) < 20 or head[:4] != b"glTF" or head[16:20] != b"JSON":
            return False
        size = int.from_bytes(head[12:16], "little")
        if size > 50_000_000:
            return False
        doc = json.loads(f.read(size))
    scenes = doc.get("scenes") if isinstance(doc, dict) else None
    extras = (
        scenes[0].get("extras", {})
        if isinstance(scenes, list) and scenes and isinstance(scenes[0], dict)
        else {}
    )
    mark = extras.get("translucency") if isinstance(extras, dict) else None
    return isinstance(mark, dict) and mark.get("written_by") == "translucency"


# -- the guards -------------------------------------------------------------------------------
def _within(inner: Path, outer: Path) -> bool:
    """``inner`` is ``outer`` or lies inside it (both resolved)."""
    return inner == outer or outer in inner.parents


def check_writable(path, option: str | None = "out") -> None:
    """Refuse, in one line naming ``option`` and ``path``, an output whose folder cannot be written: the
    nearest existing folder above ``path`` is a file, or creating an entry there fails (no permission, a
    read-only or a system file system such as /proc). Tried with a folder created and removed at once."""
    path = Path(path)
    folder = path.absolute().parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    name = f"{option} {path}" if option else str(path)
    if not folder.is_dir():
        raise TranslucencyError(
            f"{name}: {folder} is a file, not a folder; choose another path for the output"
        )
    try:
        probe = tempfile.mkdtemp(prefix=".translucency-probe-", dir=folder)
    except OSError as exc:
        why = {errno.EACCES: "permission denied", errno.EPERM: "permission denied", errno.EROFS: "read-only"}
        reason = why.get(exc.errno, "it takes no new files")
        raise TranslucencyError(
            f"{name}: the folder {folder} cannot be written ({reason}); choose a folder you can write to"
        ) from None
    os.rmdir(probe)


#: the name endings of the tool's files, and the kinds that must not carry them
_SUFFIXES = {
    ".zarr": ("model file", "output folder", "json summary"),
    ".model.zip": _FOLDER_KINDS + ("json summary",),
}


def _check_name(path: Path, kind: str, option: str) -> None:
    """Refuse an output named like another kind (a model file ``x.zarr``, a data set ``x.model.zip``)."""
    for suffix, kinds in _SUFFIXES.items():
        if path.name.endswith(suffix) and kind in kinds:
            named = "a data set" if suffix == ".zarr" else "a model file"
            raise TranslucencyError(
                f"{option} {path}: names {named} ({suffix}), but this writes {_a(kind)}; give another name"
            )


def claim_output(
    path, kind: str, *, overwrite: bool, inputs=(), option: str = "out", reuse: bool = False
) -> bool:
    """Check that ``path`` may be written as a ``kind``; return whether an old one of that kind is there.

    Parameters
    ----------
    path : path
        The output.
    kind : str
        One of :data:`KINDS`; for data sets the other data-set kind is refused.
    overwrite : bool
        An existing output of this kind may be replaced.
    inputs : iterable of path
        The command's inputs: never the output, never inside it, never holding it.
    option : str
        The argument named in messages (``"out"``; the command line passes its flag).
    reuse : bool
        The caller reopens an existing output of this kind (an acquisition that
        resumes): it is not refused without ``overwrite``.

    Returns
    -------
    bool
        True when ``path`` exists and is the tool's own ``kind``.

    Raises
    ------
    TranslucencyError
        One line naming ``path``: the current folder or one above it, an input,
        a foreign file or folder, or an own output without ``overwrite``.
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    path = Path(path)
    check_writable(path, option)
    _check_name(path, kind, option)
    target = path.resolve()
    cwd = Path.cwd().resolve()
    if _within(cwd, target):
        raise TranslucencyError(
            f"{option} {path}: is the current folder or a folder above it; give a new path for the output"
        )
    if target.parent == target or target == Path.home().resolve():
        raise TranslucencyError(
            f"{option} {path}: refusing the root or home folder; give a new path for the output"
        )
    for inp in inputs:
        if inp is None:
            continue
        src = Path(inp).resolve()
        if _within(src, target) or _within(target, src):
            raise TranslucencyError(
                f"{option} {path}: is, holds or lies inside the input {inp}; give another path for the output"
            )
    if not (path.exists() or path.is_symlink()):
        return False
    if (
        kind in _FOLDER_KINDS
        and path.is_dir()
        and not path.is_symlink()
        and {p.name for p in path.iterdir()} <= {MARKER}
    ):
        return False  # an empty folder (or one a failed command only marked) is as good as a new one
    if path.is_symlink():
        raise TranslucencyError(f"{option} {path}: is a symbolic link; give a new path for the output")
    found = kind_of(path)
    if found != kind:
        what = "a translucency " + found if found else "not a translucency " + kind
        if found:
            what += f", not {_a(kind)}"
        raise TranslucencyError(
            f"{option} {path}: exists and is {what}; refusing to replace it — give a new path for the output"
        )
    if not overwrite and not reuse:
        raise TranslucencyError(
            f"{option} {path}: {_a(kind)} written by translucency is already there; "
            "choose another path or pass overwrite=True to replace it"
        )
    return True


def remove_dataset(path) -> None:
    """Remove a data set the tool wrote: its Zarr nodes only, then the folder if nothing else is left.

    Only child folders that are Zarr nodes (hold a ``zarr.json``), the root
    ``zarr.json`` and the tool's lock file are removed; anything else inside
    stays, with a warning, and so does the folder that holds it.
    """
    path = Path(path)
    if kind_of(path) not in DATASET_KEYS:
        raise TranslucencyError(f"{path}: not a translucency data set; nothing removed")
    for child in path.iterdir():
        if child.is_dir() and not child.is_symlink() and (child / "zarr.json").is_file():
            shutil.rmtree(child)
    for name in ("zarr.json", ".translucency.lock"):
        (path / name).unlink(missing_ok=True)
    left = sorted(p.name for p in path.iterdir())
    if left:
        warnings.warn(
            f"{path}: kept {len(left)} entries translucency did not write: {left[:5]}", stacklevel=2
        )
    else:
        path.rmdir()


def reopen_or_clear(
    path, kind: str, request: dict, opener, *, overwrite: bool, inputs=(), resume: bool = True, option="out"
):
    """The resumable-output rule of the data sets: returns the one at ``path`` to resume, or None to create.

    A ``kind`` data set at ``path`` made with the same ``request`` is reopened (``opener(path)``) so that
    its finished chunks are kept — unless ``resume`` is False (data written whole); one made with other
    arguments is removed with ``overwrite`` (:func:`remove_dataset`) and refused without; anything else
    is never touched (:func:`claim_output`; ``option`` as there).
    """
    path = Path(path)
    if not claim_output(path, kind, overwrite=overwrite, inputs=inputs, option=option, reuse=True):
        return None
    try:
        old = opener(path)
    except TranslucencyError:
        old = None
    if resume and old is not None and old.header.get("request") == request:  # the same acquisition
        return old
    if not overwrite:
        raise TranslucencyError(
            f"{option} {path}: {_a(kind)} made with other arguments is already there; "
            "choose another path or pass overwrite=True to replace it"
        )
    remove_dataset(path)
    return None


def claim_folder(path, *, overwrite: bool, inputs=(), option: str = "out") -> Path:
    """Make ``path`` an output folder of the tool (created, or empty, or one it wrote before).

    A new or empty folder gets the marker file :data:`MARKER`; a folder with
    the marker is reused only with ``overwrite`` (files written there again
    replace their old versions, nothing else is removed); any other folder
    that holds files is refused.

    Returns
    -------
    Path
        ``path``, existing and marked.
    """

    path = Path(path)
    claim_output(path, "output folder", overwrite=overwrite, inputs=inputs, option=option)
    path.mkdir(parents=True, exist_ok=True)
    marker = path / MARKER
    if not marker.exists():
        tmp = marker.with_name(marker.name + f".tmp-{os.getpid()}")
        tmp.write_text(json.dumps({"written_by": "translucency", "version": __version__}) + "\n")
        os.replace(tmp, marker)
    return path


def release_output(path, before: set | None) -> None:
    """Undo a claim of an output folder by a run that failed: remove what it added, nothing else.

    ``before`` is the set of entry names the folder held when it was claimed (None: the folder did not
    exist, so it goes whole, if it is still the tool's own).  Entries that were there before stay
    (replaced files cannot be restored; they were the tool's own outputs, replaced with ``overwrite``).
    """
    path = Path(path)
    if not path.is_dir() or path.is_symlink() or kind_of(path) != "output folder":
        return
    for child in path.iterdir():
        if before is not None and child.name in before:
            continue
        if child.is_dir() and not child.is_symlink():
            shutil.rmtree(child, ignore_errors=True)
        else:
            child.unlink(missing_ok=True)
    if before is None:
        try:
            path.rmdir()
        except OSError:  # something appeared there meanwhile: kept
            pass


@contextmanager
def output_lock(path):
    """Hold ``.NAME.lock`` beside ``path`` while writing it: a second process is stopped in one line.

    The lock file holds the writer's process id; a lock left by a process that no longer runs (killed,
    crashed, power cut) is taken over.  Creation is atomic (``O_CREAT | O_EXCL``), so of two processes
    starting together exactly one wins.
    """
    path = Path(path)
    lock = path.parent / f".{path.name}.lock"
    lock.parent.mkdir(parents=True, exist_ok=True)
    for _ in range(2):  # the second try follows the removal of a stale lock
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            try:
                pid = int(lock.read_text().strip() or 0)
            except (OSError, ValueError):
                pid = 0
            if pid and pid != os.getpid() and _alive(pid):
                raise TranslucencyError(
                    f"{path}: another translucency process (pid {pid}) is writing it; wait for it to finish, "
                    f"or remove {lock} if that process is gone"
                ) from None
            lock.unlink(missing_ok=True)  # stale: its writer is gone
            continue
        with os.fdopen(fd, "w") as f:
            f.write(str(os.getpid()))
        break
    else:
        raise TranslucencyError(f"{path}: could not take the lock {lock}")
    try:
        yield lock
    finally:
        lock.unlink(missing_ok=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, another user's
        return True
    return True
