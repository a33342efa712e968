r"""Virtual DISCO on a 3D object: pencil beams at surface points, exits tallied per vertex.

For each incident vertex :math:`x_i` (a farthest-point sample of the mesh's
vertices) N photons per channel enter along the inward normal
(:mod:`translucency.acquire.mesh_walk`); each photon leaving the surface through
a triangle is shared among its three vertices by its barycentric coordinates
:math:`\phi_v` (:func:`splat_exits`), and

.. math:: R_d(x_i, v) = \frac{\sum_{\text{exits}} \phi_v}{N A_v}\quad[\mathrm{mm}^{-2}],

with :math:`A_v = \int \phi_v\, dA` the vertex's area (a third of its
triangles'): the count and the area it is divided by agree by construction.  Light
reflected by Fresnel at the entry is recorded apart (``specular``).

**Unscattered light** (``unscattered="apart"``, the default): a photon that leaves without having
scattered — the beam crossing a thin part (a horn, an ear) — flies on along the beam: a delta in
direction that a camera sees only head-on, and never the diffuse glow the exitance R_d stands for.  It is
recorded apart, the fraction of each beam that left so (``unscattered``, per point and channel), and
left out of R_d.  Counted in R_d (``"counted"``, the data sets made before), it was drawn as diffuse light
and turned a back-lit potato's thin parts pale blue-grey: the oracle of that case, every vertex a source,
reads 0.456 from the reference with it and 0.284 without (``benchmarks/objects_budget.py --orders``,
docs/through-body.md).

**Angles** (:mod:`translucency.angles`): with an :class:`~translucency.angles.Incidence` of oblique
directions each incident point is also lit from them (N photons each, reflected and refracted at the
surface), written to ``R_d_oblique``; with :class:`~translucency.angles.ExitBins` every exit is also
counted in its direction bin, ``exit_bins`` (the part of R_d, normal and oblique, that left through
each bin).  The cost is N × directions × 3 channels photons per point; the tally per photon is the
same walk.

The result is a mesh data set (:mod:`translucency.io.mesh_dataset`), written
chunk by chunk.  Same arguments resume; other arguments are refused unless
``overwrite``.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import trimesh

from .._validate import TranslucencyError, plain
from ..angles import ExitBins, Incidence, angle_record
from ..cluster import open_cluster, parse_scheduler
from ..geometry import farthest_points, tangent_frames, vertex_areas
from ..io.mesh_dataset import create_mesh_dataset, mesh_header
from ..io.outputs import output_lock
from ..mitsuba import mesh_scene
from .mesh_walk import EXIT, mesh_random_walk
from .samples import make_sample
from .volume import Volume


def acquire_mesh(
    mesh,
    volume: Volume,
    out,
    *,
    n_points: int = 64,
    photons: int = 20_000,
    seed: int = 0,
    chunk_points: int = 8,
    index_matched: bool = False,
    reentry: bool = True,
    unscattered: str = "apart",
    incidence: Incidence | None = None,
    exit_bins: ExitBins | None = None,
    overwrite: bool = False,
    inputs=(),
    progress: Callable[[int, int], None] | None = None,
    scheduler: str | None = "threads",
):
    """Scan pencil beams over a closed mesh filled with ``volume``; write a mesh data set.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Closed surface in mm (see :func:`translucency.io.mesh.load_mesh`).
    volume : Volume
        Coefficients over the mesh's bounding box (object space; z index 0 at the top).
    out : path
        Zarr directory.
    n_points, photons, seed, chunk_points
        Incident vertices, photons per point and channel, seed, points per chunk.
    reentry : bool
        Follow light that leaves one part of the mesh through the air into another (a horn beside the
        head): tallied where it finally escapes, as a photograph sees it
        (:func:`~translucency.acquire.mesh_walk.mesh_random_walk`).  Data sets made before it was
        followed read ``reentry: false`` (absent from their request).
    unscattered : {"apart", "counted"}
        Light that leaves without scattering: recorded apart and left out of R_d (module notes), or
        counted in R_d as the data sets made before (their request has no ``unscattered``).
    incidence : Incidence, optional
        Oblique beams besides the normal one at every incident point (module notes); default: the normal
        only, as the paper's data.
    exit_bins : ExitBins, optional
        Also tally each exit by its direction (module notes).
    scheduler : str, optional
        ``"threads"`` (default: this process), ``"local:N"`` or ``"tcp://HOST:PORT"``
        (:mod:`translucency.cluster`): each chunk a task that writes its rows and its done flag
        (``out`` must be visible to the workers); the data are the same bit for bit.

    Returns
    -------
    pathlib.Path
    """
    _refuse_options(photons, unscattered, scheduler)
    check_filling(mesh, volume)
    incident = farthest_points(np.asarray(mesh.vertices), n_points)
    incidence = incidence or Incidence()
    angles = angle_record(incidence, exit_bins)
    request = _request(
        mesh, volume, len(incident), photons, seed, chunk_points, index_matched, reentry, unscattered, angles
    )
    area = vertex_areas(mesh)
    header = _header(mesh, volume, len(incident), photons, seed, index_matched, request, angles)
    with output_lock(out):  # one writer at a time
        ds = create_mesh_dataset(
            out, header, mesh, area, incident, chunk_points=chunk_points, overwrite=overwrite, inputs=inputs
        )
        walk = (photons, seed, index_matched, reentry, incidence, exit_bins, unscattered == "apart")
        _scan_chunks(ds, mesh, volume, area, incident, chunk_points, walk, scheduler, progress)
        return Path(out)


def _refuse_options(photons: int, unscattered: str, scheduler: str | None) -> None:
    """Refuse, in one line before any work, a photon count, unscattered mode or scheduler out of range."""
    if photons < 1:
        raise TranslucencyError(f"photons: must be >= 1, got {photons}")
    if unscattered not in UNSCATTERED:
        raise TranslucencyError(f"unscattered: expected one of {', '.join(UNSCATTERED)}, got {unscattered!r}")
    parse_scheduler(scheduler)  # a bad option is one line before any work


def _request(
    mesh, volume: Volume, P: int, photons, seed, chunk_points, index_matched, reentry, unscattered, angles
) -> dict:
    """The scan's request as recorded (JSON round-tripped): what a resume must match."""
    request = {
        "n_points": P,
        "photons": int(photons),
        "seed": int(seed),
        "chunk": int(chunk_points),
        "index_matched": bool(index_matched),
        "reentry": bool(reentry),
        "vertices": len(mesh.vertices),
        "faces": len(mesh.faces),
        "volume": volume.description,
        "bounds": np.round(mesh.bounds, 6).tolist(),
        "volume_grid": {"voxel_mm": volume.voxel_mm, "size_mm": list(volume.size_mm)},
        "tally": "barycentric",
    }
    if unscattered == "apart":  # (absent otherwise: the data sets made before resume as they were)
        request["unscattered"] = "apart"
    if angles:  # (absent otherwise: the data sets made before the axes existed resume as they were)
        request["angles"] = angles
    return json.loads(json.dumps(request))


def _header(mesh, volume: Volume, P: int, photons, seed, index_matched: bool, request: dict, angles) -> dict:
    """The data set's header: sizes, the medium, the request, the boundary's η and a user's filling."""
    header = mesh_header(
        n_points=P,
        n_vertices=len(mesh.vertices),
        photons=photons,
        seed=seed,
        eta=volume.eta,  # the medium's own index
        g=volume.g,
        sample=volume.description,
        request=request,
        boundary_eta=1.0 if index_matched else float(volume.eta),  # what light crosses at the surface
        **({"angles": angles} if angles else {}),
    )
    if volume.description.get("generator") == "file":  # a user's filling: where it is and what it was
        header["filling"] = filling_record(volume.description["path"])
    return header


def _scan_chunks(
    ds, mesh, volume: Volume, area, incident, chunk_points: int, walk, scheduler, progress
) -> None:
    """Acquire the chunks not yet done, here or on a cluster, reporting the points finished."""
    P = len(incident)
    root = ds.group
    n_chunks = root["chunk_done"].shape[0]
    done = np.asarray(root["chunk_done"][...])
    todo = [(c, c * chunk_points, min(P, (c + 1) * chunk_points)) for c in range(n_chunks) if not done[c]]
    finished = P - sum(hi - lo for _, lo, hi in todo)
    with open_cluster(scheduler) as cluster:
        if cluster is None:  # this process, chunk after chunk (Dr.Jit uses every core)
            scene = mesh_scene(mesh)
            for c, lo, hi in todo:
                _acquire_mesh_chunk(mesh, volume, area, ds, c, lo, hi, incident[lo:hi], walk, scene)
                finished += hi - lo
                if progress:
                    progress(finished, P)
        else:  # a task per chunk: each builds the scene once per worker, writes its rows and flag
            shared = (cluster.keep(mesh), cluster.keep(volume), cluster.keep(area))
            tasks = [(ds, c, lo, hi, incident[lo:hi], walk) for c, lo, hi in todo]
            for i, _ in cluster.run(_acquire_mesh_chunk, tasks, shared=shared):
                finished += todo[i][2] - todo[i][1]
                if progress:
                    progress(finished, P)


def check_filling(mesh, volume: Volume) -> None:
    """Refuse, in one line, a filling that does not cover the mesh's bounding box (before any work)."""
    need = np.asarray(mesh.extents) - np.asarray(volume.size_mm)
    if (need > 1e-6).any():
        raise TranslucencyError(
            f"volume: {plain(volume.size_mm)} mm does not cover the mesh's bounding box "
            f"{plain(mesh.extents)} mm"
        )


def filling_record(path) -> dict:
    """A user's filling file as a data set records it: its absolute ``path`` and ``sha256`` (so that the
    reference of a model acquired from it can be rendered while the file is unchanged)."""
    path = Path(path).resolve()
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while block := f.read(1 << 22):
            h.update(block)
    return {"path": str(path), "sha256": h.hexdigest()}


#: the variance of the barycentric tally of a vertex over its Poisson value R_d / (N A_v): a photon adds
#: its barycentric weights φ_v, so Var = N E[φ²] = N E[φ] (A/6)/(A/3) for exits spread evenly over the
#: vertex's triangles; σ² = R_d / (2 N A_v) mm⁻⁴ (:mod:`translucency.evaluate.mesh_errors` measures it)
TALLY_VARIANCE_FACTOR = 0.5

#: what becomes of the light that leaves without scattering (:func:`acquire_mesh`, module notes)
UNSCATTERED = ("apart", "counted")

#: per process: (mesh, its Mitsuba scene) of the acquisition running there
_SCENE: list = []


def _acquire_mesh_chunk(mesh, volume, area, ds, c, lo, hi, incident, walk, scene=None) -> None:
    """Trace chunk ``c`` (incident vertices ``incident``, points lo..hi), write its rows, then its flag.

    ``walk`` = (photons, seed, index_matched, reentry, incidence, exit_bins, apart) — ``apart``: the
    unscattered exits left out of R_d and recorded in ``unscattered``.  A pure function of its
    arguments: here or on a worker (which builds the scene once per mesh), again after an interruption, it
    writes the same bytes.  Direction 0 (the normal) draws the same photons as before the angle axes
    existed; direction d another stream.
    """
    photons, seed, index_matched, reentry, incidence, exit_bins, apart = walk
    if scene is None:
        if not _SCENE or _SCENE[0] is not mesh:
            _SCENE[:] = [mesh, mesh_scene(mesh)]
        scene = _SCENE[1]
    root = ds.group
    V, n = len(mesh.vertices), hi - lo
    normals = np.asarray(mesh.vertex_normals)
    toward = incidence.world(tangent_frames(normals[incident]))  # (n, D, 3) toward the light
    eta = 1.0 if index_matched else float(volume.eta)
    every = {"write_empty_chunks": True}  # every chunk written is a file, zeros too: a missing one is damage
    for d in range(incidence.count):
        R = np.zeros((n, V, 3), np.float32)
        spec = np.zeros((n, 3), np.float32)
        direct = np.zeros((n, 3), np.float32)  # the fraction that left unscattered (apart)
        binned = None if exit_bins is None else np.zeros((n, V, 3, exit_bins.count), np.float32)
        for ch in range(3):
            res = mesh_random_walk(
                scene,
                mesh.bounds,
                volume,
                ch,
                mesh.vertices[incident],
                normals[incident],
                photons,
                seed=seed + 7919 * ch + 104_729 * d,
                first_point=lo,
                index_matched=index_matched,
                reentry=reentry,
                incoming=None if d == 0 else -toward[:, d],
            )
            point = np.repeat(np.arange(n), photons)
            ok = res.code == EXIT
            if apart:  # the beam that crossed without scattering: a delta along it, not in R_d
                straight = ok & (res.scatters == 0)
                direct[:, ch] = np.bincount(point[straight], minlength=n) / photons
                ok &= ~straight
            tri, bary = exit_barycentric(mesh, res.face[ok], res.position[ok])  # once for both tallies
            R[..., ch] = splat_barycentric(tri, bary, point[ok], n, V) / (photons * area)
            spec[:, ch] = np.bincount(point[res.code == -1], minlength=n) / photons
            if binned is not None:
                omega = exit_direction(mesh, res, ok, eta, reentry)
                away = res.position[ok] - mesh.vertices[incident][point[ok]]  # x_o − x_i
                b = exit_bins.index(omega, mesh.face_normals[res.face[ok]], away)
                counts = splat_barycentric(tri, bary, point[ok] * exit_bins.count + b, n * exit_bins.count, V)
                counts = counts.reshape(n, exit_bins.count, V).transpose(0, 2, 1)
                binned[..., ch, :] = counts / (photons * area)[None, :, None]
        if d == 0:
            root["R_d"].with_config(every)[lo:hi] = R
            root["specular"].with_config(every)[lo:hi] = spec
            if apart:
                root["unscattered"].with_config(every)[lo:hi] = direct
        else:
            root["R_d_oblique"].with_config(every)[lo:hi, d - 1] = R
            root["specular_oblique"].with_config(every)[lo:hi, d - 1] = spec
        if binned is not None:
            root["exit_bins"].with_config(every)[lo:hi, d] = binned
    root["chunk_done"][c] = True  # last: the chunk is complete


def exit_direction(mesh, res, ok: np.ndarray, eta: float, reentry: bool) -> np.ndarray:
    """The direction in the air of each exit ``ok`` (n, 3): the walk's own where it refracted the photon
    out (re-entry followed), else the flight inside refracted through the exit face (Snell, η → 1)."""
    omega = np.asarray(res.direction[ok], np.float64)
    if reentry or eta == 1.0:
        return omega
    m = mesh.face_normals[res.face[ok]]  # outward: along the flight of a photon leaving
    cos_i = np.einsum("nk,nk->n", omega, m)
    cos2_t = np.maximum(1.0 - eta**2 * (1.0 - cos_i**2), 0.0)  # (TIR photons did not leave)
    out = eta * omega + (np.sqrt(cos2_t) - eta * cos_i)[:, None] * m
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def splat_exits(mesh, point: np.ndarray, face: np.ndarray, position: np.ndarray, n_points: int) -> np.ndarray:
    r"""Exits shared among the vertices of their triangle by barycentric weight: (n_points, V) counts.

    An exit at y in triangle (a, b, c) adds its barycentric coordinates :math:`\phi_a(y), \phi_b(y),
    \phi_c(y)` (summing to 1) to the three vertices.  Since :math:`\int \phi_v\, dA = A_v` (a third of
    the adjacent triangles' area, :func:`translucency.geometry.vertex_areas`), dividing by N A_v gives
    the :math:`\phi_v`-weighted mean of R_d around v — the count and the area agree by construction.
    """
    tri, bary = exit_barycentric(mesh, face, position)
    return splat_barycentric(tri, bary, point, n_points, len(mesh.vertices))


def splat_barycentric(
    tri: np.ndarray, bary: np.ndarray, point: np.ndarray, n_points: int, V: int
) -> np.ndarray:
    """:func:`splat_exits` of exits whose triangles' vertices ``tri`` and barycentric coordinates ``bary``
    (:func:`exit_barycentric`) are known: (n_points, V) counts, exit e counted in row ``point[e]``."""
    index = (np.asarray(point)[:, None] * V + tri).ravel()
    return np.bincount(index, weights=bary.ravel(), minlength=n_points * V).reshape(n_points, V)


def exit_barycentric(mesh, face: np.ndarray, position: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each exit's triangle's vertices (n, 3) and its barycentric coordinates there (n, 3), clipped to the
    triangle and summing to 1 (exits lie on their face up to round-off)."""
    tri = np.asarray(mesh.faces)[face]  # (n, 3) vertex indices
    corners = np.asarray(mesh.vertices, dtype=np.float64)[tri]  # (n, 3, 3)
    bary = trimesh.triangles.points_to_barycentric(corners, np.asarray(position, dtype=np.float64))
    bary = np.clip(np.nan_to_num(bary, nan=1.0 / 3.0), 0.0, None)
    bary /= np.maximum(bary.sum(axis=1, keepdims=True), 1e-12)
    return tri, bary


def object_volume(name: str, mesh, voxel_mm: float, *, g: float = 0.0, seed: int = 0) -> Volume:
    """A generated sample (``make_sample`` names) sized to the mesh's bounding box."""

    size = tuple(float(np.ceil(e / voxel_mm) * voxel_mm) for e in mesh.extents)
    return make_sample(name, size, voxel_mm, g=g, seed=seed)
