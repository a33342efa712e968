"""The example files into a folder of the user's: what the documentation's commands read
(``translucency examples``)."""

from __future__ import annotations

import filecmp
import shutil
import sys
import tempfile
from pathlib import Path

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


#: the coarse fitted object ``spot_coarse.model.zip``: spot.obj's triangles kept, the generated filling's
#: voxel (mm), its incident points and photons per point and channel.  A fitted object to render, export
#: and view at once (the documentation's examples use it): ``spot.obj`` reduced by quadric decimation (the
#: ``viewer`` extra), acquired in generated marble, index-matched (photon seed 1), and the isotropic model
#: with two terms fitted per vertex, stored as float16 (about 40 kB; a minute to make).  A sketch to try
#: things on, not a measurement.  Regenerate it: ``python -m translucency.workflow.examples [FOLDER]``
COARSE_FACES, COARSE_VOXEL_MM, COARSE_POINTS, COARSE_PHOTONS = 800, 2.0, 12, 2000


def coarse_model(path, *, seed: int = 1) -> Path:
    """Acquire and fit the coarse example object (``spot_coarse.model.zip``) into ``path``; returns it.

    Its record names the data set only as ``spot_coarse.zarr`` (the scratch folder it was acquired in
    is gone); its acquisition header stays whole, so the filling is rebuilt for a reference render.
    """
    # the meshes, the stages and the model file load only when the model is made (copying needs none)
    from ..io.mesh import load_mesh
    from ..io.model_file import save_model
    from .acquiring import acquire_mesh
    from .fitting import fit_model

    mesh = load_mesh(example_path("spot.obj")).simplify_quadric_decimation(face_count=COARSE_FACES)
    with tempfile.TemporaryDirectory(prefix="translucency-examples-") as scratch:
        data = acquire_mesh(
            mesh, Path(scratch) / "spot_coarse.zarr", "marble", voxel_mm=COARSE_VOXEL_MM,
            points=COARSE_POINTS, photons=COARSE_PHOTONS, seed=seed, index_matched=True,
        )  # fmt: skip
        result = fit_model(data, "iso", n_terms=2).result
    return save_model(result.model, path, dtype="float16", meta=result.metadata("spot_coarse.zarr"),
                      overwrite=True)  # fmt: skip


if __name__ == "__main__":  # pragma: no cover
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else example_path("spot.obj").parent
    written = coarse_model(folder / "spot_coarse.model.zip")
    print(written, written.stat().st_size, "bytes")
