r"""A lab's object: multi-view HDR photographs of a laser stepped over a scanned mesh → a mesh data set.

``translucency import object RIG`` (:func:`import_object`) writes what ``acquire mesh`` writes —
:math:`R_d(x_i, v)` in mm⁻² per unit incident power for every vertex v of the mesh and every laser
position x_i (snapped to its nearest vertex), in a :mod:`translucency.io.mesh_dataset` — plus, per
pair, its variance (``R_d_var``) and what kept it from being measured (``flags``):

1. **Cameras** (:mod:`.object_setup`, :mod:`.cameras`): K and distortion given or by OpenCV from
   checkerboards, the pose given or by ``solvePnP`` from marked points; reprojection errors above the
   bound refused; a mesh most of whose vertices project outside every image refused.
2. **Visibility, once per camera** (:mod:`.surface_map`): Mitsuba casts a ray through every pixel
   centre; the map W (vertex × pixel) of barycentric weight × footprint area defines the per-vertex
   value exactly as the tally does.
3. **Radiance per frame**: :math:`L = (Z - \text{dark})/(k\,t\,\text{vig}\,\text{flat})/P`
   (:mod:`.object_setup`); saturated or non-finite pixels are unusable; several frames are combined
   per pixel weighted by exposure time; the variance is the noise model's, or — where two or more
   frames share an exposure — the larger of it and the frames' own scatter (which also holds what the
   noise model does not know, e.g. a renderer's Monte Carlo noise).
4. **Exitance per camera and vertex**: :math:`M_{vc} = \pi \bar L_{vc}/\gamma(\mu_{vc}, r)` with the
   exit's angular law γ (:mod:`.exit_law`; from the views by default, for an index-matched boundary).
5. **Fusion over cameras** that see at least ``min_coverage`` of the vertex's cell with usable pixels:
   weights :math:`w_c = n_c\,\gamma_c` (:math:`n_c = (\sum_p W)^2/\sum_p W^2` the cell's effective
   number of pixels: with photon noise, Var M ∝ 1/(n γ)), which do not depend on the measured values
   (inverse *measured* variances would favour the camera that read low).
6. **Flags** (bits): :data:`UNSEEN` no camera sees the cell well (its value is filled over the mesh
   graph from measured neighbours, harmonic fill), :data:`SATURATED` a camera saw it saturated,
   :data:`GRAZING` only at grazing angles, :data:`SPOT` within ``spot_radius_mm`` of the hit.  The
   per-vertex fit leaves flagged pairs out; the stored value keeps the energy bookkeeping whole.

Laser shots are processed in chunks (the unit of resuming and of memory); same arguments resume, other
arguments are refused unless ``overwrite``.  Units: mm, W, seconds; R_d in mm⁻².
"""

from __future__ import annotations

import json
import os
import time
import warnings
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from .._validate import TranslucencyError, plain
from ..geometry import vertex_areas
from ..io.mesh_dataset import create_mesh_dataset, mesh_header, open_mesh_dataset
from ..io.outputs import output_lock, remove_dataset
from ..mitsuba import mesh_scene, rays
from .cameras import Camera
from .exit_law import Dielectric, ExitLaw, Lambertian, fit_from_views, law_named
from .hdr import read_hdr
from .object_setup import CameraSetup, ObjectRig, ObjectShot, calibrated_camera, read_object_rig
from .provenance import sha256_file
from .surface_map import SurfaceMap, projects_inside, surface_map

#: flag bits of ``flags`` (P, V) uint8
UNSEEN, SATURATED, GRAZING, SPOT = 1, 2, 4, 8

#: the least fraction of the mesh's vertices that must project into some camera's image
MIN_PROJECTED = 0.5

#: the laser shots the exit law is estimated from (the first ones)
LAW_SHOTS = 16

#: the views the exit law is estimated from reach this close to grazing (degrees from the normal)
LAW_GRAZING_DEG = 85.0

#: the farthest a laser hit given as a point may lie from the surface, in mean edge lengths
HIT_TOLERANCE_EDGES = 0.5

#: a camera's view of a cell is fused only where it covers at least this fraction of what the best
#: camera covers: a view of part of a cell measures the mean over that part, not the cell's mean
FUSED_COVERAGE = 0.9


@dataclass
class _Camera:
    """A calibrated camera with its map and its corrected frames (read once)."""

    camera: Camera
    map: SurfaceMap
    setup: CameraSetup
    dark_u: np.ndarray  # (n, 3) float32 raw value at the pixels the map uses
    gain_u: np.ndarray  # (n, 3) float32: k · vig · flat — raw value per unit radiance per second


def import_object(
    rig,
    out,
    *,
    chunk_points: int = 8,
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
    exit_law: str | None = None,
) -> dict:
    """Turn a lab's object rig (``object.json``, :mod:`.object_setup`) into a mesh data set at ``out``.

    Parameters
    ----------
    rig : path
        The rig file, or the folder holding ``object.json``.
    out : path
        The mesh data set (Zarr directory) to write.
    chunk_points : int
        Laser shots per chunk (the unit of resuming; memory holds one chunk of images).
    exit_law : str, optional
        Overrides the rig file's ``exit_law`` (``"lambertian"``, ``"dielectric"``, ``"from-views"``).

    Returns
    -------
    dict
        ``path``, ``cameras`` (reprojection errors, vertices seen), ``exit_law``, ``energy`` (per shot:
        Σ_v A_v R_d per channel), ``flags`` (counts), ``seconds`` and ``bytes_read`` (image bytes).
    """
    from ..io.mesh import load_mesh  # heavy: trimesh loads where a mesh is read

    t0 = time.perf_counter()
    if chunk_points < 1:
        raise TranslucencyError(f"chunk_points: must be >= 1, got {chunk_points}")
    setup = read_object_rig(rig)
    law_name = exit_law or setup.exit_law
    fixed_law = law_named(law_name, setup.eta)
    mesh = load_mesh(setup.mesh_file, scale_mm=setup.scale_mm, up=setup.up)
    scene = mesh_scene(mesh)
    area = vertex_areas(mesh)
    V = len(mesh.vertices)
    posed = [calibrated_camera(c, setup.folder, setup.max_reprojection_px) for c in setup.cameras]
    _check_mesh_seen(mesh, posed, setup)  # before the maps: a wrong mesh is named as such, not as a camera
    cameras = [_prepare_camera(c, cam, setup, mesh, scene) for c, cam in zip(setup.cameras, posed)]
    incident, hits = _incident_vertices(setup, mesh, scene)
    P = len(incident)
    if fixed_law is None and len(cameras) < 2:
        raise TranslucencyError(
            f"{setup.path}: exit_law 'from-views' needs two cameras or more; "
            "give 'lambertian' or 'dielectric'"
        )
    law = fixed_law
    if law is None:  # estimated from the first shots (reading them once more below)
        try:
            # the law sees views closer to grazing than the data do: its normalisation needs them
            law_cams = [
                _prepare_camera(c, cam.camera, setup, mesh, scene, grazing_deg=LAW_GRAZING_DEG)
                for c, cam in zip(setup.cameras, cameras)
            ]
            law = _law_from_views(setup, law_cams, setup.shots[:LAW_SHOTS], mesh, hits, area)
        except TranslucencyError as exc:  # too few views of one vertex: say so, and take π L
            warnings.warn(f"{setup.path}: {exc} — imported with the Lambertian law instead", stacklevel=2)
            law = Lambertian()
    sample = setup.sample or {}
    request = {
        "rig": str(setup.path.resolve()),
        "rig_sha256": sha256_file(setup.path),
        "chunk": int(chunk_points),
        "exit_law": law.describe(),
        "vertices": V,
        "faces": len(mesh.faces),
        "bounds": np.round(mesh.bounds, 6).tolist(),
        "index_matched": setup.eta == 1.0,
        # a virtual rig's filling (so that a reference can be rendered as for `acquire mesh`); a lab has none
        "volume": sample.get("description", {"source": "photographs"}),
        "volume_grid": sample.get("volume_grid"),
    }
    request = json.loads(json.dumps(request))
    header = mesh_header(
        n_points=P,
        n_vertices=V,
        photons=0,  # set from the measured noise once the data are in (the fit's weights)
        seed=0,
        # the medium's index (recorded apart when the boundary is index-matched, as `acquire mesh` does)
        eta=(setup.raw.get("boundary") or {}).get("medium_eta", setup.eta),
        g=sample.get("description", {}).get("g", 0.0),
        sample=sample.get("description", {"source": "photographs"}),
        request=request,
        source="photographs",
        photographs=_provenance(setup, cameras, hits, law),
    )
    bytes_read = 0
    energy = np.zeros((P, 3))
    flag_counts = np.zeros(4, dtype=np.int64)
    fresh = not Path(out).exists() or not any(Path(out).iterdir())  # a refused import removes what it made
    try:
        with output_lock(out):
            ds = create_mesh_dataset(
                out,
                header,
                mesh,
                area,
                incident,
                chunk_points=chunk_points,
                overwrite=overwrite,
                inputs=setup.files,
                measured=True,
            )
            root = ds.group
            done = np.asarray(root["chunk_done"][...])
            finished = int(
                sum(min(P, (c + 1) * chunk_points) - c * chunk_points for c in range(len(done)) if done[c])
            )
            fill = _Filler(mesh)
            every = {"write_empty_chunks": True}
            for c in range(len(done)):
                lo, hi = c * chunk_points, min(P, (c + 1) * chunk_points)
                if done[c]:
                    R = np.asarray(root["R_d"][lo:hi], dtype=np.float64)
                    energy[lo:hi] = np.einsum("pvk,v->pk", R, area)
                    continue
                R = np.zeros((hi - lo, V, 3), np.float32)
                var = np.zeros((hi - lo, V, 3), np.float32)
                flags = np.zeros((hi - lo, V), np.uint8)
                for j in range(lo, hi):
                    shot = setup.shots[j]
                    r = np.linalg.norm(mesh.vertices - hits[j], axis=1)
                    per_cam, nbytes = _shot_cell_means(shot, cameras, setup, law, hits[j])
                    bytes_read += nbytes
                    Rj, vj, fj = _fuse(per_cam, cameras, area, setup)
                    fj[r <= setup.spot_radius_mm] |= SPOT
                    Rj = fill(Rj, (fj & (UNSEEN | SATURATED)) != 0)
                    vj[~np.isfinite(vj)] = 0.0
                    R[j - lo], var[j - lo], flags[j - lo] = Rj, vj, fj
                    energy[j] = area @ Rj
                root["R_d"].with_config(every)[lo:hi] = R
                root["R_d_var"].with_config(every)[lo:hi] = var
                root["flags"].with_config(every)[lo:hi] = flags
                root["specular"].with_config(every)[lo:hi] = np.zeros((hi - lo, 3), np.float32)
                root["chunk_done"][c] = True
                finished += hi - lo
                if progress:
                    progress(finished, P)
            flags_all = np.asarray(root["flags"][...])
            for b, bit in enumerate((UNSEEN, SATURATED, GRAZING, SPOT)):
                flag_counts[b] = int(((flags_all & bit) != 0).sum())
            header["photons"] = _equivalent_photons(root, area, flags_all)
            root.attrs.update({"translucency_mesh_dataset": header})
    except (TranslucencyError, KeyboardInterrupt):
        if fresh and Path(out).exists() and not _finished_any(out):
            remove_dataset(out)
        raise
    return {
        "path": str(out),
        "cameras": [
            {
                "name": c.camera.name,
                "reprojection_px": c.camera.reprojection_px,
                "vertices_seen": int((c.map.den > 0).sum()),
            }
            for c in cameras
        ],
        "exit_law": law.describe(),
        "energy": energy.tolist(),
        "flags": dict(zip(("unseen", "saturated", "grazing", "spot"), flag_counts.tolist())),
        "seconds": time.perf_counter() - t0,
        "bytes_read": bytes_read,
        "incident": incident.tolist(),
    }


def _finished_any(out) -> bool:
    """Whether the data set at ``out`` holds a finished chunk (kept for resuming when interrupted)."""
    try:
        return bool(np.asarray(open_mesh_dataset(out)["chunk_done"][...]).any())
    except TranslucencyError:
        return False


# -- cameras -----------------------------------------------------------------------------------------------


def _vignetting(width: int, height: int, coeffs) -> np.ndarray:
    """1 + k1 ρ² + k2 ρ⁴ + … with ρ from the image centre in half-diagonals (H·W,)."""
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    rho2 = ((u - (width - 1) / 2) ** 2 + (v - (height - 1) / 2) ** 2) / (0.25 * (width**2 + height**2))
    vig = np.ones_like(rho2)
    for i, c in enumerate(coeffs, start=1):
        vig += c * rho2**i
    return vig.ravel()


def _frame_file(path: Path, shape, what: str) -> np.ndarray:
    image = read_hdr(path)
    if image.shape[:2] != shape:
        raise TranslucencyError(
            f"{path}: {what} is {image.shape[1]} x {image.shape[0]} px, the camera {shape[1]} x {shape[0]}"
        )
    if not np.isfinite(image).all():
        raise TranslucencyError(f"{path}: {what} holds non-finite pixels")
    return image.reshape(-1, 3)


def _prepare_camera(
    setup: CameraSetup, camera: Camera, rig: ObjectRig, mesh, scene, grazing_deg=None
) -> _Camera:
    shape = (setup.height, setup.width)
    rad = setup.radiometry
    n_pix = shape[0] * shape[1]
    dark = _frame_file(rad.dark, shape, "dark frame").astype(np.float64) if rad.dark else np.zeros((n_pix, 3))
    flat = _frame_file(rad.flat, shape, "flat field").astype(np.float64) if rad.flat else np.ones((n_pix, 3))
    if (flat <= 0).any():
        raise TranslucencyError(f"{rad.flat}: flat field must be positive everywhere")
    flat = flat / flat.mean()  # normalised here: k is the response of a mean pixel
    vig = _vignetting(setup.width, setup.height, rad.vignetting)
    if (vig <= 0).any():
        raise TranslucencyError(f"camera {setup.name}: vignetting {plain(rad.vignetting)} is not positive")
    gain = rad.k * vig[:, None] * flat
    m = surface_map(mesh, camera, grazing_deg=grazing_deg or rig.grazing_deg, scene=scene)
    return _Camera(camera, m, setup, dark[m.used].astype(np.float32), gain[m.used].astype(np.float32))


def _check_mesh_seen(mesh, cameras: list[Camera], rig: ObjectRig) -> None:
    """Refuse a mesh that is not the one the cameras saw: most vertices outside every image."""
    fraction = float(np.logical_or.reduce([projects_inside(mesh, cam) for cam in cameras]).mean())
    if fraction < MIN_PROJECTED:
        raise TranslucencyError(
            f"{rig.mesh_file}: only {100 * fraction:.0f} % of the mesh's vertices project into any camera's "
            "image: is it the object the cameras saw (mesh.scale_mm, mesh.up, the poses)?"
        )


# -- laser hits --------------------------------------------------------------------------------------------


def _incident_vertices(rig: ObjectRig, mesh, scene) -> tuple[np.ndarray, np.ndarray]:
    """Each shot's hit as a point on the surface (P, 3) and its nearest vertex (P,); a hit off the mesh,
    on a back-facing side or out of range is refused in one line naming the shot."""
    from scipy.spatial import cKDTree  # heavy: SciPy's spatial index loads where hits are snapped

    verts = np.asarray(mesh.vertices, dtype=np.float64)
    edge = float(np.mean(mesh.edges_unique_length))
    tree = cKDTree(verts)
    points = np.zeros((len(rig.shots), 3))
    for shot in rig.shots:
        where = f"{rig.path}: shot {shot.index}: hit"
        h = shot.hit
        if "vertex" in h:
            v = h["vertex"]
            if not isinstance(v, int) or not 0 <= v < len(verts):
                raise TranslucencyError(f"{where}: vertex {v!r} is not a vertex index (0..{len(verts) - 1})")
            points[shot.index] = verts[v]
        elif "point" in h:
            p = np.asarray(h["point"], dtype=np.float64).ravel()
            if p.shape != (3,) or not np.isfinite(p).all():
                raise TranslucencyError(f"{where}: point must be three finite numbers (mm)")
            closest, dist = _closest_on_surface(mesh, tree, p)
            if dist > HIT_TOLERANCE_EDGES * edge:
                raise TranslucencyError(
                    f"{where}: point {plain(p)} lies {dist:.3g} mm off the mesh "
                    f"(> {HIT_TOLERANCE_EDGES} edge)"
                )
            points[shot.index] = closest
        else:
            ray = h["ray"] if isinstance(h["ray"], dict) else {}
            o = np.asarray(ray.get("origin", ()), dtype=np.float64).ravel()
            d = np.asarray(ray.get("direction", ()), dtype=np.float64).ravel()
            if o.shape != (3,) or d.shape != (3,) or not (np.isfinite(o).all() and np.isfinite(d).all()):
                raise TranslucencyError(f"{where}: ray needs origin and direction, three numbers each")
            if np.linalg.norm(d) == 0:
                raise TranslucencyError(f"{where}: ray direction is zero")
            d = d / np.linalg.norm(d)
            si = scene.ray_intersect(rays(o[None], d[None]))
            if not bool(np.asarray(si.is_valid())[0]):
                raise TranslucencyError(f"{where}: the laser ray misses the mesh")
            face = int(np.asarray(si.prim_index)[0])
            if np.dot(mesh.face_normals[face], d) >= 0:
                raise TranslucencyError(f"{where}: the laser ray hits a back-facing side of the mesh first")
            points[shot.index] = o + float(np.asarray(si.t)[0]) * d
    _, incident = tree.query(points)
    return np.asarray(incident, dtype=np.int64), points


def _closest_on_surface(mesh, tree, p: np.ndarray) -> tuple[np.ndarray, float]:
    """The surface point nearest ``p`` among the triangles around its 16 nearest vertices; its distance."""
    import trimesh  # heavy: trimesh loads where hits are snapped

    _, near = tree.query(p, k=min(16, len(mesh.vertices)))
    faces = np.unique(
        np.concatenate([mesh.vertex_faces[v][mesh.vertex_faces[v] >= 0] for v in np.atleast_1d(near)])
    )
    tri = np.asarray(mesh.triangles)[faces]
    q = trimesh.triangles.closest_point(tri, np.repeat(p[None], len(tri), axis=0))
    d = np.linalg.norm(q - p, axis=1)
    return q[np.argmin(d)], float(d.min())


# -- photographs → per-camera cell means -------------------------------------------------------------------


def _radiance(shot: ObjectShot, cam: _Camera, rig: ObjectRig):
    """One camera's frames of a shot as radiance per unit power at the pixels its map uses (n, 3), its
    variance and the usable pixels (n,) (module step 3); and the bytes read.  float32 throughout."""
    setup = cam.setup
    rad = setup.radiometry
    shape = (setup.height, setup.width)
    frames = shot.frames.get(setup.name, [])
    used = cam.map.used
    dark, gain = cam.dark_u, cam.gain_u
    num = np.zeros((len(used), 3), np.float32)
    wsum = np.zeros_like(num)
    var_model = np.zeros_like(num)
    longest = max(f.exposure_s for f in frames)
    rep_n = np.zeros(len(used), np.float32)  # repeated frames of the longest exposure: n, Σ L, Σ L²
    rep_s = np.zeros_like(num)
    rep_s2 = np.zeros_like(num)
    nbytes = 0
    for f in frames:
        raw = _frame_file(f.file, shape, "photograph")
        nbytes += raw.size * 4
        raw = raw[used]
        ok = (raw < rad.saturation).all(axis=1)
        signal = raw - dark
        scale = 1.0 / (gain * np.float32(f.exposure_s * shot.power))  # value → radiance per unit power
        L = signal * scale
        w = np.float32(f.exposure_s) * ok[:, None]  # photon noise: weight ∝ exposure
        num += w * L
        wsum += w
        var_model += w * w * (rad.gain * np.maximum(signal, 0.0) + rad.read_noise**2) * scale * scale
        if f.exposure_s == longest:
            rep_n += ok
            rep_s += ok[:, None] * L
            rep_s2 += ok[:, None] * L * L
    usable = (wsum > 0).all(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        L = np.where(wsum > 0, num / wsum, 0.0)
        var = np.where(wsum > 0, var_model / (wsum * wsum), 0.0)
        n = rep_n[:, None]
        scatter = (rep_s2 - rep_s * rep_s / n) / (n - 1) / n  # the scatter of the repeated frames' mean
    var = np.where((n >= 2) & np.isfinite(scatter), np.maximum(var, scatter), var)
    return L, var, usable, nbytes


def _shot_cell_means(shot: ObjectShot, cameras: list[_Camera], rig: ObjectRig, law=None, hit=None):
    """Per camera: (cell mean (V, 3), its variance, usable weight (V,), mean γ (V, 3)) of the radiance —
    or, with ``law``, of the exitance πL/γ converted pixel by pixel (γ at each pixel's cosine, slant
    and distance from ``hit``: the law varies across a cell near the hit); and the bytes read.  The
    cameras run on threads (reading, NumPy and the sparse products release the GIL)."""

    def one(cam: _Camera):
        if cam.setup.name not in shot.frames:
            return None, 0
        L, var, usable, nb = _radiance(shot, cam, rig)
        m = cam.map
        if law is None:
            return (*m.cell_means(L, var, usable), None), nb
        u = m.used
        if law.needs_direction:  # the slant and the distance of every pixel used
            r, slant = np.linalg.norm(m.position[u] - hit, axis=1), m.slant(hit, u)
        else:
            r = slant = np.zeros(len(u))
        gamma = law.factor(m.mu[u], slant, r).astype(np.float32)  # (n, 3)
        E, vE = np.float32(np.pi) * L / gamma, var * (np.float32(np.pi) / gamma) ** 2
        if isinstance(law, Lambertian):
            g_mean = np.ones((len(m.den), 3), np.float32)
        else:
            g_mean = m.cell_means(gamma, np.zeros_like(gamma), usable)[0]
        return (*m.cell_means(E, vE, usable), g_mean), nb

    with ThreadPoolExecutor(min(len(cameras), os.cpu_count() or 1)) as pool:
        results = list(pool.map(one, cameras))
    return [r for r, _ in results], sum(nb for _, nb in results)


def _fuse(per_cam, cameras: list[_Camera], area, rig: ObjectRig):
    """Exitance per vertex fused over cameras (module steps 4–5): R (V, 3), variance (V, 3), flags (V,)."""
    V = len(area)
    num = np.zeros((V, 3))
    den = np.zeros(V)
    var = np.zeros((V, 3))
    flags = np.zeros(V, np.uint8)
    grazing = np.zeros(V, dtype=bool)
    saturated = np.zeros(V, dtype=bool)
    weights = []
    best = np.zeros(V)  # the largest usable coverage of each cell by any camera
    for cm in per_cam:
        if cm is not None:
            best = np.maximum(best, cm[2] / np.maximum(area, 1e-30))
    for cam, cm in zip(cameras, per_cam):
        if cm is None:
            continue
        M, vM, used, gamma = cm
        m = cam.map
        grazing |= m.grazing
        seen = m.den / np.maximum(area, 1e-30) >= rig.min_coverage
        cover = used / np.maximum(area, 1e-30)
        good = seen & (cover >= rig.min_coverage)
        saturated |= seen & ~good
        good &= cover >= FUSED_COVERAGE * np.minimum(best, 1.0)
        w = np.where(good, m.n_eff * np.nan_to_num(gamma).mean(axis=1), 0.0)
        M = np.where(good[:, None], np.nan_to_num(M), 0.0)
        vM = np.where(good[:, None], np.nan_to_num(vM), 0.0)
        num += w[:, None] * M
        den += w
        weights.append((w, vM))
    measured = den > 0
    with np.errstate(invalid="ignore", divide="ignore"):
        R = np.where(measured[:, None], num / den[:, None], 0.0)
        for w, vM in weights:
            var += (w[:, None] ** 2) * vM
        var = np.where(measured[:, None], var / (den**2)[:, None], np.nan)
    flags[~measured] |= UNSEEN
    flags[~measured & saturated] |= SATURATED
    flags[~measured & grazing] |= GRAZING
    return R, var, flags


def _slant(mesh, camera: Camera, hit: np.ndarray) -> np.ndarray:
    """s = ω·t̂ per vertex: the view towards ``camera`` against the unit tangent pointing away from the hit."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    n = np.asarray(mesh.vertex_normals, dtype=np.float64)
    omega = camera.centre - v
    omega /= np.linalg.norm(omega, axis=1, keepdims=True)
    t = v - hit
    t -= np.einsum("ij,ij->i", t, n)[:, None] * n
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-12)
    return np.einsum("ij,ij->i", omega, t)


def _law_from_views(rig: ObjectRig, cameras: list[_Camera], shots, mesh, hits, area) -> ExitLaw:
    """The exit law γ estimated from vertices seen by two cameras in ``shots``
    (:func:`.exit_law.fit_from_views`)."""
    Ls, vs, mus, ss, rs = [], [], [], [], []
    for shot in shots:
        per_cam, _ = _shot_cell_means(shot, cameras, rig)
        r = np.linalg.norm(mesh.vertices - hits[shot.index], axis=1)
        L = np.full((len(cameras), len(area), 3), np.nan)
        v = np.full_like(L, np.nan)
        mu = np.zeros((len(cameras), len(area)))
        sl = np.zeros_like(mu)
        for k, (cam, cm) in enumerate(zip(cameras, per_cam)):
            if cm is None:
                continue
            good = (cm[2] / np.maximum(area, 1e-30) >= rig.min_coverage) & (r > rig.spot_radius_mm)
            good &= cam.map.den / np.maximum(area, 1e-30) >= 0.95  # views of the whole cell only
            L[k][good], v[k][good] = cm[0][good], cm[1][good]
            mu[k] = cam.map.mu_v
            sl[k] = _slant(mesh, cam.camera, hits[shot.index])
        Ls.append(L)
        vs.append(v)
        mus.append(mu)
        ss.append(sl)
        rs.append(r)
    return fit_from_views(
        np.concatenate(Ls, axis=1),
        np.concatenate(vs, axis=1),
        np.concatenate(mus, axis=1),
        np.concatenate(ss, axis=1),
        np.concatenate(rs),
    )


# -- filling, noise, provenance ----------------------------------------------------------------------------


class _Filler:
    """The harmonic fill over the mesh graph: each missing value is the mean of its neighbours', the
    measured held — :math:`(I - N_{UU}) x_U = N_{UK} x_K`, one sparse LU per set of missing vertices (the
    unseen set is the same for every shot; it changes only where a shot saturates), kept for the next.
    A component of the mesh with no measured vertex gets 0."""

    def __init__(self, mesh):
        from scipy.sparse.csgraph import connected_components  # heavy: SciPy's graphs load where filled

        e = np.asarray(mesh.edges_unique)
        V = len(mesh.vertices)
        rows, cols = np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]]
        A = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(V, V)).tocsr()
        deg = np.asarray(A.sum(axis=1)).ravel()
        self.N = (sp.diags(1.0 / np.maximum(deg, 1)) @ A).tocsr()  # row-normalised adjacency
        self.components = connected_components(self.N, directed=False)[1]
        self._cache: dict = {}

    def __call__(self, R: np.ndarray, missing: np.ndarray) -> np.ndarray:
        from scipy.sparse.linalg import splu  # heavy: SciPy's sparse LU loads where values are filled

        if not missing.any():
            return R.astype(np.float32)
        key = np.packbits(missing).tobytes()
        if key not in self._cache:
            comp = self.components
            has_known = np.zeros(comp.max() + 1, dtype=bool)
            has_known[comp[~missing]] = True
            U = np.flatnonzero(missing & has_known[comp])
            K = np.flatnonzero(~missing)
            NU = self.N[U]
            lu = splu((sp.identity(len(U), format="csc") - NU[:, U]).tocsc()) if len(U) else None
            self._cache = {key: (U, K, NU[:, K], lu)}  # one pattern kept: shots rarely alternate
        U, K, NUK, lu = self._cache[key]
        x = np.where(missing[:, None], 0.0, R).astype(np.float64)
        if len(U):
            x[U] = lu.solve(np.asarray(NUK @ x[K]))
        return x.astype(np.float32)


def _equivalent_photons(root, area, flags) -> float:
    r"""The photon count N with Poisson variance R/(N A_v) closest to the measured variance of the pairs
    above 5 σ (median): the per-vertex fit weights its pairs by that model (:mod:`translucency.fit.mesh`)."""
    R = np.asarray(root["R_d"][...], dtype=np.float64).mean(axis=2)
    var = np.asarray(root["R_d_var"][...], dtype=np.float64).mean(axis=2)
    ok = (flags == 0) & (var > 0) & (R > 5 * np.sqrt(np.maximum(var, 0)))
    if not ok.any():
        return 1.0
    A = np.broadcast_to(area[None], R.shape)
    return float(np.median(R[ok] / (var[ok] * A[ok])))


def _provenance(rig: ObjectRig, cameras: list[_Camera], hits: np.ndarray, law: ExitLaw) -> dict:
    return {
        "rig": str(rig.path.resolve()),
        "mesh": {"file": str(rig.mesh_file.resolve()), "sha256": sha256_file(rig.mesh_file)},
        "cameras": [
            {**c.camera.to_dict(), "name": c.camera.name, "reprojection_px": c.camera.reprojection_px}
            for c in cameras
        ],
        "hits_mm": np.round(hits, 6).tolist(),
        "power_W": [s.power for s in rig.shots],
        "files": [
            {cam: [str(f.file.relative_to(rig.folder)) for f in frames] for cam, frames in s.frames.items()}
            for s in rig.shots
        ],
        "exit_law": law.describe(),
        "boundary_eta": rig.eta,
        "spot_radius_mm": rig.spot_radius_mm,
        "grazing_deg": rig.grazing_deg,
        "min_coverage": rig.min_coverage,
    }


__all__ = ["import_object", "UNSEEN", "SATURATED", "GRAZING", "SPOT", "Dielectric"]
