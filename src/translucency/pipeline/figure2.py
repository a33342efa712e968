"""Figure 2: the pig acquired per vertex, fitted and rendered beside a converged volpath reference."""

from __future__ import annotations

from pathlib import Path

from ..acquire.mesh import acquire_mesh, object_volume
from ..acquire.objects import make_pig
from ..fit.mesh import fit_mesh
from ..io.model_file import save_model
from ..render import Camera, PointLight
from ..render.picture import coverage
from ..render.reference import SHIPPED as SHIPPED_REFERENCES
from ..render.reference import converged_reference
from ..render.still import render_still
from ..transport import PreparedObject, TransportOptions

#: samples per pixel of each of the two reference renders of Figure 2 (its noise: figure2.json)
FIGURE2_REFERENCE_SPP = 256


def figure2_scene(size=(160, 120)):
    """The main job's object: the pig filled with veined marble (1 mm voxels, seed 1), light, camera.

    Examples
    --------
    >>> pig, volume, light, camera = figure2_scene(size=(16, 12))
    >>> pig.is_watertight, volume.voxel_mm, (camera.width, camera.height)   # a closed mesh, mm voxels
    (True, 1.0, (16, 12))
    >>> light.position, light.intensity   # mm, W/sr
    ((60.0, -80.0, 120.0), 20000.0)
    """
    pig = make_pig()
    volume = object_volume("marble", pig, 1.0, seed=1)
    light = PointLight((60.0, -80.0, 120.0), 2.0e4)
    return pig, volume, light, Camera.looking_at(pig, width=size[0], height=size[1])


def run_figure2(
    report_dir,
    data_path,
    model_path,
    *,
    points: int = 96,
    photons: int = 8000,
    spp: int = FIGURE2_REFERENCE_SPP,
    size=(160, 120),
    overwrite: bool = False,
    paper_dir=None,
) -> dict:
    """Acquire the pig per vertex (index-matched, so that volpath can light it), fit, render, compare.

    Figure 2 is drawn as ``fit`` and ``render`` do by default: the structure chosen by held-out error,
    the fitted profiles with the model's through-body table (:mod:`translucency.model.through`).  With
    ``paper_dir`` the paper's choice is drawn there too, to set beside it (``figure2_paper.png`` /
    ``.json``, its model ``pig_paper.model.zip``): the isotropic model with n = 3 and the colour scale
    (1, s_g, s_b), rendered from its radial profiles alone (``render --paper``).

    Writes the mesh data set to ``data_path`` (resumed, or reused, if it holds the same acquisition), the
    per-vertex model to ``model_path`` (replacing an earlier one with ``overwrite``) and Figure 2 into
    ``report_dir``.  The reference is the mean of two ``spp``-sample volpath renders, shipped with the
    package for the default arguments (``make default-reference`` makes it again).

    Parameters
    ----------
    report_dir : str or Path
        Where ``figure2.png`` and ``figure2.json`` go.
    data_path, model_path : str or Path
        The mesh data set and the per-vertex model file to write.
    points, photons : int
        Incident vertices and photons per vertex and channel of the acquisition.
    spp : int
        Samples per pixel of each of the reference's two renders.
    size : (int, int)
        The picture's width and height, pixels.
    overwrite : bool
        Replace a model file at ``model_path``.
    paper_dir : str or Path, optional
        Where the paper's model's picture goes (none without).

    Returns
    -------
    dict
        Figure 2's numbers (as ``figure2.json``): the errors against the reference, its noise, the
        timings and ``speedup_vs_reference``.

    Examples
    --------
    The main job's Figure 2 (minutes: the acquisition and the fit; the reference is shipped):

    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> out = run_figure2(d / "report", d / "pig.zarr", d / "pig.model.zip")  # doctest: +SKIP
    >>> out["reference_spp"], Path(out["reference_cached"]).name  # doctest: +SKIP
    (256, 'references')
    >>> sorted(p.name for p in (d / "report").glob("figure2.*"))  # doctest: +SKIP
    ['figure2.json', 'figure2.png']
    """
    pig, volume, light, camera = figure2_scene(size)
    acquire_mesh(
        pig,
        volume,
        data_path,
        n_points=points,
        photons=photons,
        chunk_points=16,
        index_matched=True,
        overwrite=overwrite,
    )
    fit = fit_mesh(data_path)  # the default: the structure chosen by held-out error
    save_model(
        fit.model,
        model_path,
        dtype="float16",
        overwrite=overwrite,
        meta=fit.metadata(Path(data_path).resolve()),
    )
    # Figure 2 exposes its pair at the reference's own level (auto) and keeps its names
    default = render_still(
        PreparedObject(fit.model, pig),
        light,
        report_dir,
        volume=volume,
        camera=camera,
        spp_reference=spp,
        exposure="auto",
        name="figure2",
    )
    if paper_dir is not None:
        _paper_figure(data_path, paper_dir, pig, volume, light, camera, spp)
    return default


def _paper_figure(data_path, paper_dir, pig, volume, light, camera, spp: int) -> None:
    """The paper's choice fitted to the same data, drawn from its radial profiles alone into ``paper_dir``."""
    paper = fit_mesh(data_path, "iso", n_terms=3, colour="shared")  # the paper's structure
    paper_dir = Path(paper_dir)
    save_model(paper.model, paper_dir / "pig_paper.model.zip", dtype="float16", overwrite=True,
               meta=paper.metadata(Path(data_path).resolve()))  # fmt: skip
    render_still(
        PreparedObject(paper.model, pig, options=TransportOptions(kind="paper")),
        light,
        paper_dir,
        volume=volume,
        camera=camera,
        spp_reference=spp,
        exposure="auto",
        name="figure2_paper",
    )


def write_figure2_reference(folder=None, *, spp: int = FIGURE2_REFERENCE_SPP, size=(160, 120)) -> dict:
    """Render the main job's converged reference into ``folder`` (default: the shipped references).

    Parameters
    ----------
    folder : str or Path, optional
        The reference cache to look in and write to (default: the shipped references).
    spp : int
        Samples per pixel of each of the two renders.
    size : (int, int)
        The picture's width and height, pixels.

    Returns
    -------
    dict
        ``key``, ``spp``, ``noise`` (relative RMSE of the mean of the two renders), ``seconds`` (path
        tracing) and ``cached`` (the folder it was found in; None when rendered now).

    Examples
    --------
    The shipped reference was rendered at :data:`FIGURE2_REFERENCE_SPP` samples per pixel, twice:

    >>> import json
    >>> from pathlib import Path
    >>> from translucency.pipeline.figure2 import FIGURE2_REFERENCE_SPP, write_figure2_reference
    >>> from translucency.render.reference import SHIPPED as SHIPPED_REFERENCES
    >>> shipped = [json.loads(p.read_text()) for p in SHIPPED_REFERENCES.glob("*.json")]
    >>> [(ref["spp"], ref["renders"]) for ref in shipped] == [(FIGURE2_REFERENCE_SPP, 2)]
    True

    With the default arguments it is found there and nothing is rendered (a few seconds: the scene and
    its key); into another folder the two renders take about 13 minutes:

    >>> info = write_figure2_reference()
    >>> info["spp"], info["renders"], Path(info["cached"]).name
    (256, 2, 'references')
    """
    pig, volume, light, camera = figure2_scene(size)
    _, info = converged_reference(
        pig, volume, light, camera, coverage(pig, camera), spp=spp, cache=folder or SHIPPED_REFERENCES
    )
    return info
