"""What the page shows of a per-vertex model before any transport: the mesh (and a reduced one drawn
while things move), the maps per vertex and each incident point's profiles.

:func:`surface_data` takes seconds; the live viewer shows it first, while :mod:`.object_page` prepares
the transport and the transfer.  Units: mm, R_d in mm⁻².
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .._extras import require
from ..geometry import vertex_areas
from ..model.bounds import check_physics
from ..transport.parameters import neighbour_weights
from .defaults import DEFAULT_LIGHT, DEFAULT_VIEW, IRRADIANCE, POINT_DISTANCE, point_intensity
from .maps import page_maps

#: triangles of the mesh drawn while things move (software WebGL draws ~0.5 M triangles a second on 2 cores)
REDUCED_FACES = 8000
#: rings of the profiles: log-spaced radii
PROFILE_RINGS = 24


def surface_data(model, mesh, *, name: str, dataset=None) -> tuple[dict, dict]:
    """(meta, arrays) of what needs no transport: the mesh, the maps and the profiles (seconds).

    The live viewer shows these first, while the transport and the transfer are prepared.

    Examples
    --------
    >>> import trimesh, translucency as tl
    >>> mesh = trimesh.creation.icosphere(2, radius=5.0)
    >>> x = np.asarray(mesh.vertices[:2])
    >>> frame = np.repeat(np.eye(3)[None], 2, axis=0)
    >>> alpha = tl.VertexAlpha(np.ones(len(mesh.vertices)), np.asarray(mesh.vertices))
    >>> model = tl.DipoleModel(x, [[0.01] * 3] * 2, [[1.0] * 3] * 2, 1.0, alpha, frame=frame)
    >>> meta, arrays = surface_data(model, mesh, name="ball")
    >>> meta["vertices"], meta["profiles"]["count"], arrays["profile_model"].shape
    (162, 2, (2, 24, 3))
    """
    V, F = len(mesh.vertices), len(mesh.faces)
    arrays = {
        "position": np.asarray(mesh.vertices, np.float32),
        "normal": np.asarray(mesh.vertex_normals, np.float16),
        "index": np.asarray(mesh.faces, np.uint32),
    }
    maps = _maps(model, mesh, arrays)
    profiles = _profiles(model, mesh, dataset, arrays)
    _reduced_mesh(mesh, arrays)
    meta = {
        "title": name,
        "subtitle": f"{V:,} vertices, {model.n_points} incident points",
        "vertices": V,
        "faces": F,
        "centre": [float(x) for x in 0.5 * (mesh.bounds[0] + mesh.bounds[1])],
        "size": float(np.linalg.norm(mesh.extents)),
        "view": {"az": DEFAULT_VIEW[0], "el": DEFAULT_VIEW[1]},
        "default_light": {
            "kind": "directional",
            "az": DEFAULT_LIGHT[0],
            "el": DEFAULT_LIGHT[1],
            "dist": POINT_DISTANCE,
        },
        "maps": maps,
        "profiles": profiles,
        "directional_irradiance": IRRADIANCE,
        "point_intensity": point_intensity(float(np.linalg.norm(mesh.extents))),
    }
    return meta, arrays


def reduced_mesh(mesh):
    """(reduced mesh, source) — the mesh drawn while the light or the camera moves: a quadric decimation
    to :data:`REDUCED_FACES` triangles (``fast_simplification`` through trimesh), each of its vertices
    standing for the full mesh's vertex nearest it (``source``, whose attributes, transfer and draft
    relight it takes); None for a mesh no larger.

    Examples
    --------
    >>> import trimesh
    >>> reduced_mesh(trimesh.creation.icosphere(2)) is None  # 320 triangles
    True
    """
    if len(mesh.faces) <= REDUCED_FACES:
        return None
    check_reduced_mesh(len(mesh.faces))
    reduced = mesh.simplify_quadric_decimation(face_count=REDUCED_FACES)
    _, source = cKDTree(np.asarray(mesh.vertices)).query(np.asarray(reduced.vertices))
    return reduced, source


def check_reduced_mesh(n_faces: int) -> None:
    """One line, before any work, where a mesh of ``n_faces`` triangles needs a reduced mesh and the
    package that makes it (``fast_simplification``, the viewer extra) is missing.

    Examples
    --------
    >>> check_reduced_mesh(REDUCED_FACES)  # no larger: drawn as it is
    >>> check_reduced_mesh(10 * REDUCED_FACES)  # the viewer extra, installed here
    """
    if n_faces > REDUCED_FACES:
        require("viewer")


def _reduced_mesh(mesh, arrays: dict) -> None:
    """The reduced mesh's arrays for the page (``lod_position``, ``lod_index``, ``lod_source``)."""
    found = reduced_mesh(mesh)
    if found is None:
        return
    reduced, source = found
    arrays["lod_position"] = np.asarray(reduced.vertices, np.float32)
    arrays["lod_index"] = np.asarray(reduced.faces, np.uint32)
    arrays["lod_source"] = np.asarray(source, np.uint32)


def _maps(model, mesh, arrays: dict) -> list:
    """The per-vertex maps: total reflectance, 99 % energy radius, α and the physics flags."""
    w, idx = neighbour_weights(model, mesh)
    blend = lambda per_point: np.einsum("vk,vk->v", w, np.asarray(per_point, np.float64)[idx])  # noqa: E731
    check = check_physics(model, size_mm=float(np.max(mesh.extents)))
    values = {
        "map_reflectance": (
            "total diffuse reflectance (mean of R, G, B)",
            "",
            blend(model.total_reflectance().mean(axis=1)),
        ),
        "map_radius": ("99 % energy radius", "mm", blend(model.energy_radius(0.99))),
        "map_alpha": (
            "modulation texture α",
            "",
            np.asarray(model.alpha.at(np.asarray(mesh.vertices)), np.float64),
        ),
    }
    legend = (
        f"nearest incident point breaks a bound ({int(check.flagged.sum())} of {model.n_points} points): "
        f"{check.describe()}"
    )
    return page_maps(values, check.flagged[idx[:, 0]], legend, arrays)  # a vertex: its nearest point's flags


def _profiles(model, mesh, dataset, arrays: dict) -> dict:
    """Ring means of the fit's R_d around each incident point and, with the data set, the measured ones."""
    v = np.asarray(mesh.vertices, np.float64)
    area = vertex_areas(mesh)
    edge = float(np.mean(mesh.edges_unique_length))
    r_max = float(np.max(model.energy_radius(0.99)))
    edges = np.geomspace(max(edge, 1e-3), max(r_max, 2 * edge), PROFILE_RINGS + 1)
    centres = np.sqrt(edges[:-1] * edges[1:])
    N, R = model.n_points, PROFILE_RINGS
    fit = np.full((N, R, 3), np.nan)
    measured = np.full((N, R, 3), np.nan) if dataset is not None else None
    for i in range(N):
        r = np.linalg.norm(v - model.x_i[i], axis=1)
        ring = np.searchsorted(edges, r, side="right") - 1
        ok = (ring >= 0) & (ring < R)
        wsum = np.bincount(ring[ok], area[ok], minlength=R)
        with np.errstate(invalid="ignore", divide="ignore"):
            Rd = model.R_d(np.full(int(ok.sum()), i), v[ok])
            data = None if measured is None else np.asarray(dataset["R_d"][i], np.float64)[ok]
            for c in range(3):
                fit[i, :, c] = np.bincount(ring[ok], area[ok] * Rd[:, c], minlength=R) / wsum
                if measured is not None:
                    measured[i, :, c] = np.bincount(ring[ok], area[ok] * data[:, c], minlength=R) / wsum
    arrays["profile_points"] = np.asarray(model.x_i, np.float32)
    arrays["profile_model"] = np.nan_to_num(fit, nan=0.0).astype(np.float32)
    if measured is not None:
        arrays["profile_measured"] = np.nan_to_num(measured, nan=0.0).astype(np.float32)
    return {"count": N, "radii_mm": centres.tolist(), "measured": measured is not None}
