"""Evaluation as one function: a fitted model's relative L2 errors on its data set or on an independent
truth."""

from __future__ import annotations

import os
import warnings

import numpy as np

from .._validate import TranslucencyError, check_option
from ..evaluate.errors import PlanarErrors, planar_errors
from ..evaluate.mesh_errors import MeshErrors, check_same_points, mesh_errors
from ..io.dataset import PlanarDataset, dataset_identity
from ..io.mesh_dataset import MeshDataset
from ._arguments import model_and_record
from .datasets import open_dataset

__all__ = ["evaluate_model"]


def evaluate_model(
    model,
    dataset,
    *,
    truth=None,
    flagged=None,
    exclusion_mm: float | None = None,
    scheduler: str | None = "threads",
) -> PlanarErrors | MeshErrors:
    """Relative L2 errors of a fitted model on its data set, or on an independent truth.

    A planar model on a planar data set: :func:`translucency.evaluate.errors.planar_errors`; a per-vertex
    model on a mesh data set: :func:`translucency.evaluate.mesh_errors.mesh_errors` (the numbers of
    ``translucency evaluate``; the reports: :func:`translucency.evaluate.report.write_report`,
    :func:`translucency.evaluate.mesh_report.write_mesh_report`).

    Parameters
    ----------
    model : FitResult, ReflectanceModel or path
        The fit (its flagged points and exclusion radius are used), a model, or a model file (the fit's
        record in it is used).
    dataset : PlanarDataset, MeshDataset or path
        The data set the model was fitted to.
    truth : PlanarDataset, MeshDataset or path, optional
        An independent acquisition of the same incident points (another photon seed, usually more
        photons; on a mesh the same mesh and incident vertices): the errors are then held out, against
        the material rather than the fitted noise.
    flagged : array of bool, optional
        Points to leave out (default: those the fit flagged).
    exclusion_mm : float, optional
        Pairs closer than this are left out (default: the fit's, else one pixel / half the mean edge).
    scheduler : str, optional
        Where the chunks of a planar evaluation run; the errors are the same.

    Returns
    -------
    PlanarErrors or MeshErrors
        ``rel_l2`` (overall), ``bands`` (near < 1 mm, mid 1–4 mm, far > 4 mm), ``noise`` (the
        reference's noise floor), ``energy``, ``beyond_noise`` and the errors per point (and per pixel
        or per vertex).

    Raises
    ------
    TranslucencyError
        A planar model with a mesh data set or the reverse, a model of other incident points, or a
        truth of other incident points.

    Examples
    --------
    >>> import translucency as tl
    >>> data = tl.data.default_dataset()
    >>> fitting = tl.fit_model(data)  # doctest: +SKIP
    >>> errors = tl.evaluate_model(fitting.result, data, truth=tl.data.default_truth())  # doctest: +SKIP
    >>> round(errors.rel_l2, 3)  # doctest: +SKIP
    0.103
    """
    fitted, record = model_and_record("model", model)
    data = open_dataset(dataset) if isinstance(dataset, (str, os.PathLike)) else dataset
    if not isinstance(data, (PlanarDataset, MeshDataset)):
        raise TranslucencyError(f"dataset: expected a data set or its path, got {type(data).__name__}")
    geometry = getattr(fitted, "geometry", "planar")
    wanted = "mesh" if isinstance(data, MeshDataset) else "planar"
    if geometry != wanted:
        raise TranslucencyError(
            f"model: a {'per-vertex' if geometry == 'mesh' else 'planar'} model and a {wanted} data set; "
            "evaluate takes a planar model with a planar data set, or a per-vertex model with a mesh data set"
        )
    reference = data
    if truth is not None:
        reference = open_dataset(truth) if isinstance(truth, (str, os.PathLike)) else truth
        if not isinstance(reference, type(data)):
            raise TranslucencyError(
                f"truth: expected a {wanted} data set (as dataset) or its path, "
                f"got {type(reference).__name__}"
            )
        if isinstance(data, MeshDataset):
            check_same_points(data, reference)
        if dataset_identity(reference.header) != dataset_identity(data.header):
            warnings.warn(
                f"truth {reference.path}: measured another sample than {data.path}; "
                "the errors compare two materials",
                stacklevel=2,
            )
    if flagged is None:
        flagged = np.zeros(fitted.n_points, bool)
        flagged[np.asarray(record.get("flagged_points", []), dtype=int)] = True
    if exclusion_mm is None:
        exclusion_mm = (record.get("fit") or {}).get("exclusion_mm")
    check_option("exclusion_mm", exclusion_mm, lo=0)
    if isinstance(data, MeshDataset):
        return mesh_errors(fitted, reference, flagged=flagged, exclusion_mm=exclusion_mm)
    return planar_errors(fitted, reference, flagged=flagged, exclusion_mm=exclusion_mm, scheduler=scheduler)
