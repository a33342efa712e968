r"""Data sets judged by their picture: each fitted and drawn by ``render``'s chain, against each other and
against one converged ``volpath`` reference of the object they measured.

A lab judges an import by the object rendered from it, not by energy per shot.  :func:`picture_check`
fits every data set it is given the same way (``fit_mesh``, isotropic; the through-body table as ``fit``
stores it), draws each with ``render``'s default transport under one light and camera
(:func:`translucency.transport.relight.relight_object`, :class:`~translucency.render.picture.VertexPicture`),
and compares over the object's pixels: the relative RMSE
:math:`\sqrt{\sum (A - B)^2 / \sum B^2}` (:func:`translucency.render.compare.compare`) of each against the
first data set's picture and against the reference, and the brightness (mean over the object, A / B).

Units: mm; radiance per W of the light's power as ``render`` draws it.
"""

from __future__ import annotations

from pathlib import Path

from ..fit.mesh import fit_mesh
from ..io.mesh_dataset import open_mesh_dataset
from ..mitsuba import mesh_scene
from ..render import boundary_eta
from ..render.compare import compare
from ..render.picture import VertexPicture, coverage
from ..render.reference import converged_reference
from ..render.tonemap import auto_exposure, save_images
from ..transport import PreparedObject, TransportOptions


def picture_check(mesh, volume, datasets: dict, light, camera, *, eta: float = 1.0, reference_spp: int = 256,
                  angles: bool = False, out=None) -> dict:  # fmt: skip
    """Fit and draw each of ``datasets`` (name → mesh data set path; the first is the one the others are
    judged against) and compare the pictures with each other and with a converged reference.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The object, mm (the data sets' mesh).
    volume : Volume
        Its filling, for the reference.
    datasets : dict
        Name → mesh data set (``acquire mesh`` or ``import object``), the reference data set first.
    light, camera
        The render's light (:func:`translucency.render.lights.text.parse_light`) and camera.
    eta : float
        The reference's boundary (1: index-matched); each data set is drawn behind its own
        (:func:`translucency.render.boundary_eta`), as ``render`` draws it.
    reference_spp : int
        Samples per pixel of each of the reference's two renders (cached, :func:`converged_reference`).
    angles : bool
        Draw with the lean where a model has one (``render --angles``).
    out : path, optional
        Where the pictures go as EXR and PNG (one exposure, the reference's).

    Returns
    -------
    dict
        Per name: ``vs_first`` (relative RMSE against the first data set's picture; 0 for it),
        ``brightness_vs_first``, ``vs_volpath`` (relative RMSE against the reference); and
        ``reference_noise``.

    Examples
    --------
    A ball of marble scanned twice with independent photons (two mesh data sets; a lab's photographs,
    ``import object``, would be the second), both fitted and drawn, against a reference of 16 samples a
    pixel (half a minute, so not run here):

    >>> import tempfile, trimesh
    >>> import translucency as tl
    >>> from translucency.acquire.mesh import object_volume
    >>> from translucency.pipeline.picture_check import picture_check
    >>> from translucency.render import Camera
    >>> from translucency.render.lights.text import parse_light
    >>> ball, folder = trimesh.creation.icosphere(2, radius=5.0), tempfile.mkdtemp()
    >>> scan = dict(voxel_mm=1.0, points=4, photons=300, index_matched=True, sample_seed=0)
    >>> a = tl.acquire_mesh(ball, folder + "/a.zarr", "homogeneous:marble", seed=0, **scan)  # doctest: +SKIP
    >>> b = tl.acquire_mesh(ball, folder + "/b.zarr", "homogeneous:marble", seed=1, **scan)  # doctest: +SKIP
    >>> res = picture_check(ball, object_volume("homogeneous:marble", ball, 1.0), {"a": a.path, "b": b.path},
    ...                     parse_light("point:30,-40,60,2e3"), Camera.looking_at(ball, width=32, height=24),
    ...                     reference_spp=16)  # doctest: +SKIP
    >>> res["b"]["vs_first"] < res["b"]["vs_volpath"]  # doctest: +SKIP
    True
    """
    mask = coverage(mesh, camera)
    reference, info = converged_reference(mesh, volume, light, camera, mask, spp=reference_spp, eta=eta)
    exposure = auto_exposure(reference, mask)
    if out is not None:
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        save_images(reference, out / "reference", exposure)
    scene = mesh_scene(mesh)  # the shadows of one mesh: built once for every data set
    drawn = {}
    for name, data in datasets.items():
        model = fit_mesh(data, "iso").model
        eta_data = boundary_eta(open_mesh_dataset(data).header)
        prepared = PreparedObject(model, mesh, eta=eta_data, options=TransportOptions(angles=angles))
        L, _ = prepared.relight(light, camera.origin, scene=scene)
        drawn[name] = VertexPicture(mesh, camera, spp=16, eta=eta_data, light=light).draw(L)
        if out is not None:
            save_images(drawn[name], out / name, exposure)
    first = drawn[next(iter(drawn))]
    result: dict = {"reference_noise": float(info["noise"])}
    for name, image in drawn.items():
        result[name] = {
            "vs_first": float(compare(first, image, mask)["rel_rmse"]),
            "brightness_vs_first": float(image[mask].mean() / first[mask].mean()),
            "vs_volpath": float(compare(reference, image, mask)["rel_rmse"]),
            "brightness_vs_volpath": float(image[mask].mean() / reference[mask].mean()),
        }
    return result


__all__ = ["picture_check"]
