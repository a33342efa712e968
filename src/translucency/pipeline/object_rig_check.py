r"""The object rig end to end: virtual photographs → ``import object`` → the numbers of the tally.

For one mesh and filling, :func:`object_rig_check`

1. photographs the object twice with the virtual rig (:mod:`translucency.rig.object.photographs`,
   render and sensor seeds 0 and 1: two independent acquisitions) and imports both
   (:func:`translucency.rig.object.importer.import_object`) — A and B;
2. tallies the same object, filling and incident vertices with photons (``acquire mesh``,
   index-matched: the photographs' boundary) — T, whose own noise is far below the photographs';
3. compares per pair (x_i, v) over the pairs A measures (no flag) above 5 σ: the **recovery**
   :math:`\operatorname{median}|A - T|/T` against the photographs' **noise floor**
   :math:`\operatorname{median}|A - B|/(\sqrt2\, T)` (the error of one import, from two); and per shot
   the **energy** :math:`\sum_v A_v R_d(x_i, v)` of A against T's;
4. fits both per vertex (``fit_mesh``, isotropic) and renders both under one light against one
   converged ``volpath`` reference (:func:`translucency.render.still.render_still`): the photographs'
   render error against the tally's.

Units: mm; R_d in mm⁻².
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..acquire.mesh import acquire_mesh
from ..fit.mesh import fit_mesh
from ..io.mesh_dataset import open_mesh_dataset
from ..render import Camera, PointLight
from ..render.still import render_still
from ..rig.object.importer import import_object
from ..rig.object.photographs import photograph_object
from ..transport import PreparedObject


def object_rig_check(
    mesh,
    volume,
    folder,
    *,
    points: int = 4,
    cameras: int = 8,
    resolution=(96, 96),
    spp: int = 128,
    photons: int = 100_000,
    light: PointLight | None = None,
    reference_spp: int = 64,
    render: bool = True,
    reuse: bool = False,
    exit_law: str | None = None,
    progress=None,
) -> dict:
    """Run the check (module notes) in ``folder``; return its numbers (JSON-ready).

    ``light``: the render's (default a point light up and to the side at 3 object sizes).  ``reuse``:
    keep photographs and the tally already in ``folder`` (made by an earlier check with the same
    arguments) and only import, compare and render again.  ``exit_law``: the import's (default the
    rig file's, from-views).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    say = progress or (lambda text: None)
    shots = dict(n_points=points, n_cameras=cameras, resolution=resolution, spp=spp)
    imports = [
        _photographed_and_imported(mesh, volume, folder, seed, shots, reuse, exit_law, say) for seed in (0, 1)
    ]
    say("tally")
    if not (reuse and (folder / "tally.zarr").is_dir()):
        acquire_mesh(
            mesh,
            volume,
            folder / "tally.zarr",
            n_points=points,
            photons=photons,
            index_matched=True,
            overwrite=True,
        )
    out = {
        "vertices": len(mesh.vertices),
        "points": points,
        "cameras": cameras,
        "resolution": list(resolution),
        "spp": spp,
        "photons": photons,
        **_compared(folder),
        "exit_law": imports[0]["exit_law"],
        "import_seconds": imports[0]["seconds"],
        "import_MB": imports[0]["bytes_read"] / 2**20,
    }
    if render:
        out.update(_fits_rendered(mesh, volume, folder, light, reference_spp, say))
    out["seconds"] = time.perf_counter() - t0
    return out


def _photographed_and_imported(
    mesh, volume, folder: Path, seed: int, shots: dict, reuse, exit_law, say
) -> dict:
    """Step 1 for one seed: the virtual rig's photographs (kept with ``reuse``) and their import's record."""
    say(f"photographs, seed {seed}")
    if not (reuse and (folder / f"rig{seed}" / "object.json").is_file()):
        photograph_object(mesh, volume, folder / f"rig{seed}", seed=seed, **shots)
    say(f"import, seed {seed}")
    return import_object(
        folder / f"rig{seed}", folder / f"photo{seed}.zarr", overwrite=True, exit_law=exit_law
    )


def _compared(folder: Path) -> dict:
    """Step 3: A against T per pair above 5 σ (recovery, noise floor from A and B) and per shot (energy)."""
    A, B, T = (open_mesh_dataset(folder / n) for n in ("photo0.zarr", "photo1.zarr", "tally.zarr"))
    area = np.asarray(A["vertex_area"][...], dtype=np.float64)
    Ra, Rb, Rt = (np.asarray(d["R_d"][...], dtype=np.float64) for d in (A, B, T))
    va = np.asarray(A.group["R_d_var"][...], dtype=np.float64)
    flags = np.asarray(A.group["flags"][...])
    ok = (flags == 0)[..., None] & (Ra > 5 * np.sqrt(va)) & (Rt > 0)
    energy = {k: np.einsum("pvk,v->pk", R, area) for k, R in (("photo", Ra), ("tally", Rt))}
    return {
        "pairs_compared": int(ok.sum()),
        "recovery": float(np.median(np.abs(Ra - Rt)[ok] / Rt[ok])),
        "noise_floor": float(np.median(np.abs(Ra - Rb)[ok] / (np.sqrt(2) * Rt[ok]))),
        "median_ratio": float(np.median(Ra[ok] / Rt[ok])),
        "energy_photo": energy["photo"].tolist(),
        "energy_tally": energy["tally"].tolist(),
        "energy_ratio": (energy["photo"] / energy["tally"]).tolist(),
        "energy_worst": float(np.max(np.abs(energy["photo"] / energy["tally"] - 1))),
    }


def _fits_rendered(mesh, volume, folder: Path, light, reference_spp: int, say) -> dict:
    """Step 4: A and T fitted per vertex and rendered against one volpath reference; their render errors."""
    size = float(np.linalg.norm(mesh.extents))
    centre = 0.5 * (mesh.bounds[0] + mesh.bounds[1])
    light = light or PointLight(tuple(centre + size * np.array([1.0, -1.3, 2.0])), 40.0 * size**2)
    camera = Camera.looking_at(mesh, width=128, height=96)
    out = {}
    for name, data in (("photo", folder / "photo0.zarr"), ("tally", folder / "tally.zarr")):
        say(f"fit and render: {name}")
        model = fit_mesh(data, "iso").model
        res = render_still(
            PreparedObject(model, mesh),
            light,
            folder / f"render_{name}",
            volume=volume,
            camera=camera,
            spp_reference=reference_spp,
            exposure="auto",
            name=name,
        )
        out[f"render_{name}"] = {k: res[k] for k in ("rel_rmse", "flip_mean_object") if k in res}
        out["reference_noise"] = res.get("reference_noise")
    out["render_ratio"] = out["render_photo"]["rel_rmse"] / out["render_tally"]["rel_rmse"]
    return out
