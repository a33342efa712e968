"""The paper's Figure 2: a fitted object rendered beside its path-traced reference.

:func:`object_from_dataset` rebuilds the mesh (and, for generated fillings, the
volume) of a mesh data set; :func:`figure2` lights it, renders ours and the
``volpath`` reference through one camera, and writes reference | ours | FLIP
error with the numbers.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import trimesh
from scipy.ndimage import binary_erosion

from .._plotting import pyplot
from .._validate import TranslucencyError
from ..acquire.mesh import object_volume
from ..io.atomic import atomic_path, write_json
from ..io.mesh_dataset import open_mesh_dataset
from ..mitsuba import mesh_scene, rays
from .image import Camera, VertexPicture, compare, coverage, rel_rmse, save_images, tonemap
from .reference import converged_reference
from .transport import exit_fresnel, relight_vertices, transport_matrices, vertex_irradiance


def object_from_dataset(path):
    """(mesh, header) of a mesh data set (:mod:`translucency.io.mesh_dataset`)."""
    ds = open_mesh_dataset(path)
    return ds.mesh(), ds.header


def object_of_model(model, header: dict):
    """(mesh, acquisition header) of a per-vertex model file: from the model itself when it carries its
    triangles (``model.faces``, ``meta["acquisition"]``), else from its data set (older files)."""
    meta = header.get("meta", {})
    if model.faces is not None:
        mesh = trimesh.Trimesh(np.asarray(model.alpha.vertices), np.asarray(model.faces), process=False)
        return mesh, meta.get("acquisition", {})
    dataset = meta.get("dataset", "")
    if not dataset or not Path(dataset).exists():
        raise TranslucencyError(
            f"model: holds no mesh and its data set {dataset or '(none recorded)'} is gone; "
            "refit it with this version (models now carry their mesh)"
        )
    return object_from_dataset(dataset)


def volume_of_dataset(mesh, header):
    """The generated filling of a mesh data set, rebuilt from its description."""
    d = header.get("sample", {})
    if "generator" not in d or "voxel_mm" not in header.get("request", {}).get("volume_grid", {}):
        raise TranslucencyError("data set: its filling cannot be rebuilt (not generated here); no reference")
    grid = header["request"]["volume_grid"]
    return object_volume(
        d["generator"], mesh, grid["voxel_mm"], g=header.get("g", 0.0), seed=d.get("seed", 0)
    )


def boundary_eta(header) -> float:
    """η of a mesh data set's boundary: 1 when it was acquired index-matched."""
    return 1.0 if header.get("request", {}).get("index_matched", False) else float(header.get("eta", 1.0))


def figure2(
    model,
    mesh,
    light,
    out_dir,
    *,
    volume=None,
    camera: Camera | None = None,
    spp_reference: int = 32,
    radius: float | None = None,
    eta: float = 1.0,
    spp: int = 16,
    reference_cache=True,
    progress=None,
) -> dict:
    """Render ``model`` on ``mesh`` under ``light``; with ``volume`` also the reference and the comparison.

    ``eta``: the boundary the data set was acquired with (:func:`boundary_eta`);
    ≠ 1 adds the Fresnel factors, the surface reflection and a dielectric reference.
    ``spp``: samples per pixel of our picture (anti-aliasing only: at 16 the drawing adds ≲ 0.005 of
    relative error at the silhouettes). The reference is the mean of two independent renders of
    ``spp_reference`` samples each, with its noise measured and cached
    (:func:`translucency.render.reference.converged_reference`; ``reference_cache`` as there).
    ``progress(done, total, step)`` is called as each step begins (transport, light, picture, reference).

    Writes ``ours.exr/.png`` (and ``reference.exr/.png``, ``figure2.png``,
    ``figure2.json``) into ``out_dir``; returns the numbers.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    camera = camera or Camera.looking_at(mesh)
    mask = coverage(mesh, camera)
    steps = 3 if volume is None else 4

    def step(k, name):
        if progress:
            progress(k, steps, name)

    step(0, "transport (once per object)")
    t = time.perf_counter()
    mats = transport_matrices(model, mesh, radius=radius)
    picture = VertexPicture(mesh, camera, spp=spp, eta=eta, light=light)  # the scene, built once
    scene = mesh_scene(mesh)  # for shadow rays
    t_prepare = time.perf_counter() - t
    step(1, "irradiance and relight")
    t = time.perf_counter()
    E = vertex_irradiance(mesh, scene, light, eta)
    L = relight_vertices(mats, E) * exit_fresnel(mesh, camera.origin, eta)[:, None]
    t_relight = time.perf_counter() - t
    step(2, "picture")
    t = time.perf_counter()
    ours = picture.draw(L)
    t_draw = time.perf_counter() - t
    out = {
        "vertices": len(mesh.vertices),
        "transport_nonzeros": mats.nnz,
        "prepare_s": t_prepare,
        "relight_s": t_relight,
        "draw_s": t_draw,
        "light": repr(light),
        "eta": eta,
    }
    if volume is None:
        exposure = 0.8 / max(float(np.quantile(ours[mask], 0.99)), 1e-30)
        save_images(ours, out_dir / "ours", exposure)
        write_json(out_dir / "figure2.json", out)
        return out
    step(3, "volpath reference (2 renders, cached)")
    reference, ref_info = converged_reference(
        mesh, volume, light, camera, mask, spp=spp_reference, eta=eta, cache=reference_cache
    )
    t_ref = ref_info["seconds"]
    cmp = compare(reference, ours, mask)
    flip_map = cmp.pop("flip_map")
    out.update(cmp)
    out["regions"] = region_errors(mesh, scene, camera, E, reference, ours, mask)
    out.update(
        {
            "reference_s": t_ref,
            "reference_noise": ref_info["noise"],
            "reference_cached": ref_info["cached"],
            "reference_spp": spp_reference,
            "speedup_vs_reference": t_ref / (t_prepare + t_relight + t_draw),
        }
    )
    save_images(reference, out_dir / "reference", cmp["exposure"])
    save_images(ours, out_dir / "ours", cmp["exposure"])
    _plot(reference, ours, flip_map, mask, cmp, out_dir / "figure2.png")
    write_json(out_dir / "figure2.json", out)
    return out


def vertex_thickness(mesh, scene) -> np.ndarray:
    """Distance (mm) from each vertex straight inwards (along −n) to the other side of the object."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    si = scene.ray_intersect(rays(v - n * 1e-4 * float(np.max(mesh.extents)), -n))
    return np.where(np.asarray(si.is_valid()), np.asarray(si.t, dtype=np.float64), np.inf)


def region_errors(
    mesh, scene, camera: Camera, E: np.ndarray, reference: np.ndarray, ours: np.ndarray, mask: np.ndarray
) -> dict:
    """Relative RMSE of ours against the reference in the regions where a local model is expected to err.

    Regions (pixels of the object; vertex properties drawn through the camera):
    ``thin`` (< 10 mm through the object along the normal), ``thick`` (> 25 mm), ``shadow edge``
    (vertices on either side of the lit/unlit boundary, one ring wide), ``unlit`` (no direct light),
    ``silhouette`` (the outermost pixel ring of the object). Returns {region: {rel_rmse, pixels}}.
    """
    E = np.asarray(E, dtype=np.float64)
    lit = (E.sum(axis=1) if E.ndim == 2 else E) > 0
    edges = np.asarray(mesh.edges_unique)
    flip = lit[edges[:, 0]] != lit[edges[:, 1]]
    edge_v = np.zeros(len(lit), dtype=bool)
    edge_v[edges[flip].ravel()] = True
    ring = edge_v.copy()  # one ring more
    ring[edges[edge_v[edges[:, 0]] | edge_v[edges[:, 1]]].ravel()] = True
    thick = vertex_thickness(mesh, scene)
    flags = np.stack([thick < 10.0, thick > 25.0, ring], axis=1).astype(np.float64)
    picture = VertexPicture(mesh, camera, spp=1)
    drawn = picture.draw(flags) > 0.5
    unlit = picture.draw(np.repeat((~lit)[:, None], 3, axis=1).astype(np.float64))[..., 0] > 0.5
    regions = {
        "all": mask,
        "thin": drawn[..., 0] & mask,
        "thick": drawn[..., 1] & mask,
        "shadow edge": drawn[..., 2] & mask,
        "unlit": unlit & mask,
        "silhouette": mask & ~binary_erosion(mask),
    }
    return {
        name: {"rel_rmse": rel_rmse(ours, reference, sel), "pixels": int(sel.sum())}
        for name, sel in regions.items()
    }


def _plot(reference, ours, flip_map, mask, cmp, path) -> None:
    plt = pyplot()

    fig, ax = plt.subplots(1, 3, figsize=(13, 3.8))
    ax[0].imshow(tonemap(reference, cmp["exposure"]))
    ax[0].set_title("reference: Mitsuba volpath of the volume", fontsize=9)
    ax[1].imshow(tonemap(ours, cmp["exposure"]))
    ax[1].set_title("ours: fitted per-vertex model, sparse transport", fontsize=9)
    im = ax[2].imshow(np.where(mask, flip_map, np.nan), cmap="magma", vmin=0, vmax=1)
    ax[2].set_title(
        f"FLIP (object mean {cmp['flip_mean_object']:.3f}); rel. RMSE {cmp['rel_rmse']:.2f}", fontsize=9
    )
    fig.colorbar(im, ax=ax[2], shrink=0.8)
    for a in ax:
        a.axis("off")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
