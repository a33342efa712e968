"""The main job as the library runs it: :func:`translucency.pipeline.run_demo` (``translucency demo``,
``make demo``), the paper's Figure 1 on the embedded default data and Figure 2 on the alabaster pig, with
its memory estimated and checked before it starts."""

from __future__ import annotations

import os

from .. import resources
from ..acquire.objects import make_pig
from ..data import default_dataset_path
from ..fit import FAMILIES, FIT_BLOCK, default_chunk_points
from ..fit.structure import resolve_structure
from ..io.dataset import open_dataset
from ..pipeline.demo import DEMO_FITS, DEMO_STEPS
from ..pipeline.demo import run_demo as main_job
from ..resources.run import Reporter, Run
from ._arguments import refuse_unknown
from .fitting import MESH_FIT_CHUNK

__all__ = ["DEMO_STEPS", "demo_need", "run_demo"]

#: Figure 2's acquisition of the pig (:func:`translucency.pipeline.figure2.run_figure2`'s defaults):
#: incident vertices, photons, points a chunk, the filling's voxel (mm)
FIGURE2_ACQUISITION = {"points": 96, "photons": 8000, "chunk": 16, "voxel_mm": 1.0}


def run_demo(
    out_dir, *, max_memory: str | int | None = None, reporter: Reporter | None = None, **job
) -> dict:
    """Run the main job and write its outputs under ``out_dir``: :func:`translucency.pipeline.run_demo`
    after its memory (:func:`demo_need`) is checked against ``max_memory`` (default: the machine's
    available memory), refused in one line before any work.

    ``translucency demo`` is this function; ``reporter`` and the keywords ``n_terms``, ``step``,
    ``dataset``, ``max_rounds`` and ``overwrite`` as in :func:`translucency.pipeline.run_demo`, whose
    outputs it returns.

    Examples
    --------
    >>> from translucency import run_demo
    >>> run_demo("results", max_memory="1M")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: demo: needs about ... of memory (...), more than --max-memory...
    """
    refuse_unknown("run_demo", job, main_job)
    run = Run("demo", max_memory=max_memory, reporter=reporter)
    run.check(demo_need(job.get("dataset")), out_dir)
    outputs = main_job(out_dir, reporter=reporter, **job)
    run.summary({})  # the run is done: its outputs stay
    return outputs


def demo_need(dataset=None) -> resources.Need:
    """The main job's peak memory: the largest of its planar fits of ``dataset`` (default: the embedded
    data; each fit's richest structure, as ``fit`` estimates it) and Figure 2's acquisition and fit of the
    pig.  Figure 2's render is not counted: its transport's size follows the fitted model's radius.

    Examples
    --------
    >>> need = demo_need()
    >>> 0.25 < need.memory / 2**30 < 8  # GiB
    True
    """
    data = open_dataset(dataset or default_dataset_path())
    H, W = data.window
    workers = os.cpu_count() or 1
    needs = []
    for kw in DEMO_FITS.values():
        family, n, m, c, _, _ = resolve_structure(
            kw.get("model", "auto"), kw.get("n_terms"), kw.get("n_directions"), kw.get("colour"), planar=True
        )
        needs.append(
            resources.memory.planar_fit(
                points=data.n_points,
                pixels=H * W,
                chunk=default_chunk_points(data.n_points, int(data.group["R_d"].chunks[0])),
                workers=workers,
                params=FAMILIES[family].params_per_point(n, m, c),
                block=FIT_BLOCK,
            )
        )
    pig, a = make_pig(), FIGURE2_ACQUISITION
    V, F = len(pig.vertices), len(pig.faces)
    needs.append(
        resources.memory.mesh_acquisition(
            vertices=V,
            faces=F,
            points=a["points"],
            photons=a["photons"],
            chunk=a["chunk"],
            voxels=resources.memory.object_voxels(pig.extents, a["voxel_mm"]),
        )
    )
    family, n, _, c, _, _ = resolve_structure("auto", None, None, None, planar=False)
    params = FAMILIES[family].params_per_point(n, 1, c)
    needs.append(
        resources.memory.mesh_fit(
            points=a["points"], vertices=V, chunk=MESH_FIT_CHUNK, workers=workers, params=params
        )
    )
    disk = sum(need.disk for need in needs)  # every output kept
    top = max(needs, key=lambda need: need.memory)
    return resources.Need(top.memory, disk, top.what.split(":")[0])  # (the stages' flags are not the demo's)
