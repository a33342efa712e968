"""The example files into a folder of the user's: what the documentation's commands read
(``translucency examples``)."""

from __future__ import annotations

import filecmp
import shutil

from .._validate import TranslucencyError
from ..data import EXAMPLES, example_path
from ..io.atomic import atomic_path
from ..resources.run import Reporter
from ._arguments import as_path


def copy_examples(out, *, overwrite: bool = False, reporter: Reporter | None = None) -> dict:
    """Copy the example files (:data:`translucency.data.EXAMPLES`) into the folder ``out``.

    ``translucency examples OUT`` is this function.  Each file is written atomically; a file of the same
    name already in ``out`` with other contents is replaced only with ``overwrite`` (else nothing is
    written and one line names them); one with the same contents is kept as it is.

    Parameters
    ----------
    out : str or Path
        The folder (made if missing).
    overwrite : bool
        Replace files of the same names with other contents.
    reporter : Reporter, optional
        Hears one information line where files were already there (default: silent).

    Returns
    -------
    dict
        ``out`` (the folder), ``written`` and ``unchanged`` (file names).

    Examples
    --------
    >>> import tempfile, translucency as tl
    >>> folder = tempfile.mkdtemp()
    >>> sorted(tl.copy_examples(folder)["written"])
    ['LICENSES.md', 'cow.obj', 'filling.npz', 'scene.xml', 'sky.exr', 'spot.obj', 'spot_coarse.model.zip']
    >>> tl.copy_examples(folder)["unchanged"] == tl.data.EXAMPLES   # the same files: nothing to do
    True
    >>> from pathlib import Path
    >>> _ = (Path(folder) / "scene.xml").write_text("<scene version='3.0.0'/>")   # the user's own scene
    >>> tl.copy_examples(folder)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: .../scene.xml: already there with other contents ...
    """
    out = as_path("out", out)
    if out.exists() and not out.is_dir():
        raise TranslucencyError(f"the folder for the examples, {out}, is a file")
    there = [name for name in EXAMPLES if (out / name).exists()]
    folders = [str(out / name) for name in there if (out / name).is_dir()]
    if folders:
        raise TranslucencyError(f"{', '.join(folders)}: a folder where an example goes; choose another one")
    same = [name for name in there if filecmp.cmp(example_path(name), out / name, shallow=False)]
    other = [str(out / name) for name in there if name not in same]
    if other and not overwrite:
        raise TranslucencyError(
            f"{', '.join(other)}: already there with other contents than the example; "
            "choose another folder or pass overwrite=True"
        )
    written = [name for name in EXAMPLES if name not in same]
    if same and reporter is not None:
        reporter.info(f"already there, the same: {', '.join(same)}")
    for name in written:
        with atomic_path(out / name) as tmp:
            shutil.copyfile(example_path(name), tmp)
    return {"out": out, "written": tuple(written), "unchanged": tuple(same)}
