r"""What the page shows of a planar model: the sample as a flat mesh, its maps, each incident point's
profile against its data (and an independent truth), and the sample relit under a distant light.

The sample is the modulation texture's grid (one vertex per α pixel, at most :data:`MAX_SIDE` a side),
flat at z = 0 with +z up.  On a flat, index-matched sample nothing shadows anything and every incident
point sees the same sky, so the transfer is exact in closed form: a light of coefficients :math:`L_k`
gives each point the irradiance :math:`E = \sum_k L_k E^{(k)}`,
:math:`E^{(k)} = \int Y_k(\omega) \cos^+\theta\, d\omega`, and the sample leaves
:math:`B_o = a_o E` with :math:`a_o = \alpha(x_o)\, \rho(x_o) / \pi` — its response to a uniform
irradiance, ρ the total diffuse reflectance of the nearest incident points (blended as the maps are).
The page stores it in the per-vertex format of :mod:`.transfer_codec` (the rest r = 0,
:math:`\bar E = E^{(k)}`, local = a), so one page serves both.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..evaluate.rings import ring_stats
from ..model.bounds import check_physics
from ..render.lights import EnvironmentLight
from ..transport import sh
from ..transport.transfer import DEFAULT_BANDS, Transfer
from .defaults import DEFAULT_LIGHT, IRRADIANCE, POINT_DISTANCE, point_intensity
from .maps import page_maps
from .object_page import EXIT_TABLE
from .transfer_codec import encode_transfer

#: the most vertices along a side of the sample's mesh
MAX_SIDE = 192


def planar_page_data(
    model, *, name: str, dataset=None, truth=None, bands: int = DEFAULT_BANDS
) -> tuple[dict, dict]:
    """(meta, arrays) of the whole page of a planar ``model`` (module docstring); ``dataset``: the planar
    data set it was fitted to (its windows' ring means), ``truth``: an independent acquisition of the same
    points."""
    xs, ys, xy, faces = _flat_mesh(model.alpha)
    V = len(xy)
    position = np.concatenate([xy, np.zeros((V, 1))], axis=1)
    wts, near = _blend_weights(model, xy)
    rho = _blend(wts, near, model.total_reflectance())  # (V, 3)
    a_alpha = np.asarray(model.alpha.at(xy), np.float64)
    check = check_physics(model)
    maps_values = {
        "map_alpha": ("modulation texture α", "", a_alpha),
        "map_reflectance": ("total diffuse reflectance (mean of R, G, B)", "", rho.mean(axis=1)),
        "map_radius": ("99 % energy radius", "mm", _blend(wts, near, model.energy_radius(0.99))),
    }
    arrays = {
        "position": position.astype(np.float32),
        "normal": np.tile(np.array([0.0, 0.0, 1.0], np.float16), (V, 1)),
        "index": faces.astype(np.uint32),
    }
    legend = f"nearest incident point breaks a bound: {check.describe()}"
    maps = page_maps(maps_values, check.flagged[near[:, 0]], legend, arrays)
    profiles = _profiles(model, dataset, truth, arrays)
    # the relighting: every point alike, Ē = E^(k), local a = α ρ / π and t = a Ē (the rest r = 0)
    local = np.clip(a_alpha[:, None] * rho / np.pi, 0.0, None)
    transfer_meta, transfer_arrays = encode_transfer(_flat_transfer(local, bands))
    arrays.update(transfer_arrays)
    meta = _page_meta(model, name, (xs, ys), len(faces), maps, profiles, transfer_meta, local, bands)
    return meta, arrays


def _flat_mesh(alpha) -> tuple:
    """The flat mesh on α's grid: pixel centres xs, ys (mm), the vertices' (x, y), two triangles a cell."""
    H, W = alpha.shape
    step = max(1, -(-max(H, W) // MAX_SIDE))
    rows, cols = np.arange(0, H, step), np.arange(0, W, step)
    xs = alpha.origin[0] + (cols + 0.5) * alpha.pitch
    ys = alpha.origin[1] + (rows + 0.5) * alpha.pitch
    X, Y = np.meshgrid(xs, ys)
    xy = np.stack([X.ravel(), Y.ravel()], axis=1)
    idx = np.arange(len(xy)).reshape(len(rows), len(cols))
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1], idx[1:, 1:]
    faces = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    return xs, ys, xy, faces


def _blend_weights(model, xy) -> tuple[np.ndarray, np.ndarray]:
    """Each vertex's 4 nearest incident points (V, k) and their inverse-square-distance weights (sum 1)."""
    V = len(xy)
    k = min(4, model.n_points)
    dist, near = cKDTree(model.x_i[:, :2]).query(xy, k=k)
    dist, near = dist.reshape(V, k), near.reshape(V, k)
    wts = 1.0 / np.maximum(dist, 1e-9) ** 2
    wts /= wts.sum(axis=1, keepdims=True)
    return wts, near


def _blend(wts, near, per_point) -> np.ndarray:
    """A per-point quantity blended at every vertex with its nearest points' weights."""
    return np.einsum("vk,vk...->v...", wts, np.asarray(per_point, np.float64)[near])


def _flat_transfer(local, bands: int) -> Transfer:
    """The flat sample's exact transfer: every vertex sees E^(k) = ∫ Y_k cos⁺θ dω, leaves local times it."""
    lattice = sh.sphere_directions(4096)
    Ek = sh.basis(lattice, bands).T @ np.maximum(lattice[:, 2], 0.0) * (4 * np.pi / len(lattice))  # (K,)
    return Transfer(
        coefficients=local[:, None, :] * Ek[None, :, None],
        irradiance=np.broadcast_to(Ek, (len(local), len(Ek))),
        local=local,
        bands=bands,
        directions=len(lattice),
    )


def _page_meta(model, name, centres, n_faces, maps, profiles, transfer_meta, local, bands) -> dict:
    """The page's meta: title, mesh, view and lights, maps, profiles, transfer and exposure."""
    alpha, (xs, ys) = model.alpha, centres
    H, W = alpha.shape
    size = float(np.hypot(xs[-1] - xs[0], ys[-1] - ys[0])) or 1.0
    environment = EnvironmentLight(IRRADIANCE / np.pi)
    bright = float(np.quantile(local.max(axis=1), 0.99)) * IRRADIANCE
    return {
        "title": name,
        "subtitle": f"planar sample, {H} x {W} α pixels of {alpha.pitch:g} mm, "
        f"{model.n_points} incident points",
        "vertices": len(xs) * len(ys),
        "faces": n_faces,
        "centre": [float(xs.mean()), float(ys.mean()), 0.0],
        "size": size,
        "view": {"az": -90.0, "el": 60.0},
        "default_light": {"kind": "directional", "az": DEFAULT_LIGHT[0], "el": 60.0, "dist": POINT_DISTANCE},
        "maps": maps,
        "profiles": profiles,
        "directional_irradiance": IRRADIANCE,
        "point_intensity": point_intensity(size),
        "distant_only": True,
        **transfer_meta,
        "exit_law": False,
        "exit_table_size": EXIT_TABLE,
        "eta": 1.0,
        "exposure": 0.5 / bright if bright > 0 else 1.0,
        "blur_mm": 0.0,
        "env": {"coefficients": environment.sh_coefficients(bands).tolist()},
        "errors": {},
        "about": "A flat, index-matched sample: nothing shadows, every point sees the same sky, so the "
        "relit sample is α ρ / π times the irradiance (exact for the paper's model with a Lambertian exit).",
        "live": False,
    }


def _profiles(model, dataset, truth, arrays: dict) -> dict | None:
    """Ring means (one-pixel rings) of the fit's R_d in each incident point's window, of the data's and of
    the truth's; without a data set, the fit's on rings of the α pitch out to its 99 % energy radius."""
    N = model.n_points
    if dataset is None:
        pitch = float(model.alpha.pitch)
        n = int(np.clip(np.max(model.energy_radius(0.99)) / pitch, 4, 64))
        window = (2 * n + 1, 2 * n + 1)
        origin = model.x_i[:, :2] - n * pitch - pitch / 2
    else:
        pitch, window = dataset.pitch, tuple(dataset.window)
        origin = dataset["window_origin"].astype(np.float64)
    fit, data, true = [], [], []
    for i in range(N):
        pred = model.R_d_window([i], origin[i : i + 1], pitch, window)[0]
        r, m, _ = zip(*(ring_stats(pred[:, :, c], None, pitch) for c in range(3)))
        fit.append(np.stack(m, axis=1))
        for store, out in ((dataset, data), (truth, true)):
            if store is not None:
                win = np.asarray(store["R_d"][i], np.float64)
                out.append(np.stack([ring_stats(win[:, :, c], None, pitch)[1] for c in range(3)], axis=1))
    radii = np.asarray(r[0])
    arrays["profile_points"] = np.concatenate([model.x_i[:, :2], np.zeros((N, 1))], axis=1).astype(np.float32)
    arrays["profile_model"] = np.nan_to_num(np.stack(fit)).astype(np.float32)
    if data:
        arrays["profile_measured"] = np.nan_to_num(np.stack(data)).astype(np.float32)
    if true:
        arrays["profile_truth"] = np.nan_to_num(np.stack(true)).astype(np.float32)
    return {"count": N, "radii_mm": radii.tolist(), "measured": bool(data), "truth": bool(true)}
