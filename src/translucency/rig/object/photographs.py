r"""A virtual object rig: Mitsuba 3 photographs of a filled mesh lit by a laser, from calibrated cameras.

What a lab hands over for ``translucency import object`` (:mod:`.setup`), made without a lab:

* **the object**: the mesh filled with a volume (one grey channel at a time), behind an index-matched
  ``null`` boundary (:func:`translucency.mitsuba.scenes.object_volpath_scene`);
* **the laser**: at each incident vertex :math:`x_i` (the farthest-point sample ``acquire mesh``
  takes) a Mitsuba ``spot`` at :math:`x_i + D n_i` aimed along :math:`-n_i`, lighting a disc of
  ``beam_radius_mm`` (its power from the spot's fall-off, :class:`LaserBeam`).  A *pencil* beam
  cannot be rendered: camera paths inside the medium must reach the light by next-event estimation
  through the boundary, and only those that scatter inside the beam's cylinder do; a 0.3 mm disc keeps
  that chance workable at tens of samples per pixel, and the difference from a pencil is confined to
  the spot (masked by ``spot_radius_mm``).  Point emitters along the beam line were tried and dropped:
  their 1/d² contributions have infinite variance in a scattering medium (the renders came out 20–30 %
  low at 1,024 samples per pixel), and they miss the light that leaves after one scattering;
* **the cameras**: ``n_cameras`` distortion-free pinholes on a sphere around the object
  (:class:`.cameras.Camera`), each photograph rendered twice with independent seeds (repeated
  frames: their scatter is the photographs' Monte Carlo noise) plus one short exposure (for the
  saturated spot), exposed by the sensor model of :class:`translucency.rig.shared.sensor.Sensor`
  (gain, photon and read noise, dark offset, vignetting, flat field, saturation) under a laser power
  that drifts from shot to shot (recorded as a power monitor would);
* **calibration**: each camera's pose as marked points (12 vertices it sees, their projections with
  0.15 px of noise) and, if asked, checkerboard photographs for its intrinsics.

``truth.json`` beside ``object.json`` records the true cameras (for tests; the import never reads it).
Units: mm, W; radiance per W of laser power.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..._validate import TranslucencyError
from ...geometry import farthest_points
from ...io.atomic import atomic_path, write_json
from ...mitsuba import mesh_scene, mitsuba, object_volpath_scene, object_window_scene, rays, spot_dict
from ..shared.hdr import write_hdr
from ..shared.sensor import Sensor
from ..shared.spot import spot_power
from .cameras import Camera
from .setup import FORMAT, VERSION
from .surface_map import surface_map
from .targets import render_checkerboards

#: the short exposure's length relative to the long one (the spot unsaturated in it)
SHORT_EXPOSURE = 0.02


@dataclass(frozen=True)
class LaserBeam:
    """A spot ``distance_mm`` from the surface lighting a disc of ``radius_mm`` (Mitsuba's linear fall-off
    from :data:`translucency.mitsuba.SPOT_BEAM_FRACTION` of the cutoff; its power
    :func:`translucency.rig.shared.spot.spot_power`).

    Examples
    --------
    The spot keeps its disc wherever it sits: half as far, its cone is twice as wide and its power per
    unit intensity four times as large (the solid angle, to small-angle accuracy):

    >>> beam = LaserBeam(radius_mm=0.3, distance_mm=60.0)
    >>> round(beam.cutoff_deg(60.0), 4), round(beam.cutoff_deg(30.0) / beam.cutoff_deg(60.0), 4)
    (0.2865, 2.0)
    >>> round(beam.power(30.0) / beam.power(60.0), 3)
    4.0
    """

    radius_mm: float = 0.3
    distance_mm: float = 60.0

    def cutoff_deg(self, distance_mm: float) -> float:
        return float(np.degrees(np.arctan(self.radius_mm / distance_mm)))

    def power(self, distance_mm: float) -> float:
        """Power (W) per unit intensity (W/sr): 2π ∫ f(θ) sin θ dθ over the cone."""
        return spot_power(self.cutoff_deg(distance_mm))


def cameras_around(mesh, n: int, width: int, height: int, *, fov_deg: float = 30.0, seed: int = 0) -> list:
    """``n`` cameras on a sphere around the object (a Fibonacci spiral, slightly turned by ``seed``), each
    looking at the bounding box's centre from where the object fills ~85 % of the narrower field."""
    if n < 1:
        raise TranslucencyError(f"cameras: need at least 1, got {n}")
    centre = 0.5 * (mesh.bounds[0] + mesh.bounds[1])
    radius = 0.5 * float(np.linalg.norm(mesh.extents))
    half = np.radians(fov_deg) / 2 * min(1.0, height / width)
    dist = radius / np.sin(0.85 * half)
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n * 0.9 - 0.05  # keep off the poles (the up hint)
    phi = np.pi * (1 + 5**0.5) * k + 0.7 * seed
    dirs = np.column_stack([np.sqrt(1 - z**2) * np.cos(phi), np.sqrt(1 - z**2) * np.sin(phi), z])
    return [
        Camera.looking_at(centre + dist * d, centre, width, height, fov_deg=fov_deg, name=f"cam{i}")
        for i, d in enumerate(dirs)
    ]


def _beam_distance(scene, point, normal, beam: LaserBeam) -> float:
    """How far from the surface the spot can sit without the object in the way (mm)."""
    si = scene.ray_intersect(rays((point + 1e-3 * normal)[None], normal[None]))
    t = float(np.asarray(si.t)[0]) if bool(np.asarray(si.is_valid())[0]) else np.inf
    return float(min(beam.distance_mm, 0.9 * t))


def window_mesh(mesh, point, beam: LaserBeam):
    """The mesh with its faces within 1 mm of ``point`` subdivided to edges of a third of the beam's radius,
    and which of its faces form the window over the laser's disc (those whose centroid lies within the
    radius plus one fine edge of ``point``): a (vertices, faces, window) triple for
    :func:`translucency.mitsuba.object_window_scene`.  (The fine faces meet their coarse neighbours at
    T-junctions: the surface is the same, every new vertex on an old edge.)

    Examples
    --------
    >>> import trimesh
    >>> ball = trimesh.creation.icosphere(2, radius=6.0)
    >>> fine, window = window_mesh(ball, ball.vertices[0], LaserBeam(radius_mm=0.3))
    >>> d = np.linalg.norm(fine.triangles_center - ball.vertices[0], axis=1)
    >>> bool(window[d <= 0.3].all()), bool(window[d > 0.45].any())  # the disc, and no more than its rim
    (True, False)
    >>> bool(np.allclose(fine.area, ball.area))  # the same surface
    True
    """
    import trimesh  # heavy: trimesh loads where a mesh is refined

    point = np.asarray(point, dtype=np.float64)
    edge = beam.radius_mm / 3.0
    V, F = np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces)
    for _ in range(12):
        tri = V[F]
        near = np.linalg.norm(tri.mean(axis=1) - point, axis=1) <= 1.0 + np.linalg.norm(
            tri[:, 0] - tri[:, 1], axis=1
        )
        longest = np.max(np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2), axis=1)
        refine = np.flatnonzero(near & (longest > edge))
        if len(refine) == 0:
            break
        V, F = trimesh.remesh.subdivide(V, F, face_index=refine)
    fine = trimesh.Trimesh(V, F, process=False)
    window = np.linalg.norm(fine.triangles_center - point, axis=1) <= beam.radius_mm + edge
    return fine, window


def render_shot(
    mesh,
    volume,
    camera: Camera,
    point,
    normal,
    beam: LaserBeam,
    *,
    spp: int,
    seed: int,
    scene,
    eta: float = 1.0,
):
    """Radiance (H, W, 3) per W of laser power entering at ``point`` along −``normal``, one grey
    ``volpath`` render per channel.  ``eta`` > 1: behind a smooth dielectric of that index, the laser
    entering through a window over its disc (:func:`window_mesh`) with Fresnel's transmittance at normal
    incidence, 1 − ((η − 1)/(η + 1))² (its reflected part, the glint, is not rendered)."""
    mi = mitsuba()
    D = _beam_distance(scene, point, normal, beam)
    emitter = spot_dict(point + D * normal, point, beam.cutoff_deg(D), 1.0)
    out = np.zeros((camera.height, camera.width, 3), np.float32)
    if eta != 1.0:
        fine, window = window_mesh(mesh, point, beam)
    for ch in range(3):
        if eta == 1.0:
            sc = object_volpath_scene(mesh, volume, ch, emitter, camera.sensor_dict(spp))
        else:
            sc = object_window_scene(fine, window, volume, ch, emitter, camera.sensor_dict(spp), eta=eta)
        out[..., ch] = np.asarray(mi.render(sc, spp=int(spp), seed=int(seed) * 3 + ch))[..., ch]
    transmitted = 1.0 - ((eta - 1.0) / (eta + 1.0)) ** 2
    return out * transmitted / beam.power(D)


def _marks(mesh, camera: Camera, rng, n: int = 12, noise_px: float = 0.15) -> dict:
    """``n`` vertices the camera sees face-on, spread out, and where they project (plus noise)."""
    m = surface_map(mesh, camera)
    seen = np.flatnonzero((m.den > 0) & (m.mu_v > 0.5))
    if len(seen) < n:
        raise TranslucencyError(f"{camera.name}: sees fewer than {n} vertices to mark")
    pick = seen[farthest_points(np.asarray(mesh.vertices)[seen], n)]
    X = np.asarray(mesh.vertices, dtype=np.float64)[pick]
    uv = camera.project(X) + noise_px * rng.standard_normal((n, 2))
    return {"object_mm": X.tolist(), "image_px": uv.tolist()}


def photograph_object(
    mesh,
    volume,
    folder,
    *,
    n_points: int = 8,
    cameras=None,
    n_cameras: int = 6,
    resolution: tuple[int, int] = (128, 128),
    spp: int = 64,
    seed: int = 0,
    sensor: Sensor | None = None,
    beam: LaserBeam | None = None,
    image_format: str = "pfm",
    checkerboards: bool = False,
    spot_radius_mm: float = 0.5,
    exposures: str = "brackets",
    boundary_eta: float = 1.0,
    progress=None,
) -> dict:
    """Photograph ``volume`` inside ``mesh`` lit at ``n_points`` vertices; write a lab's hand-over.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The closed object, mm.
    volume : Volume
        Its filling over the mesh's bounding box (``acquire mesh``'s ``object_volume``); its η is
        recorded as the medium's (the boundary is index-matched).
    folder : path
        Where ``object.json``, ``object.ply``, ``cam*/`` and ``shots/`` go (created).
    cameras : list of Camera, optional
        Default :func:`cameras_around` (``n_cameras`` at ``resolution`` = (width, height)).
    spp : int
        Samples per pixel of each of the two repeated frames.
    boundary_eta : float
        1: index-matched (``null``); > 1: a smooth dielectric of that index (the volume's η replaced; the
        laser through a window over its disc, :func:`render_shot`; ``spot_radius_mm`` at least the
        window's, which the import then sets aside).
    exposures : {"brackets", "single"}
        ``"brackets"``: per camera and shot, two repeated long exposures and a short one (the spot
        unsaturated in it); ``"single"``: one long exposure, the spot clipped, as a lab's single
        exposure is.
    sensor : Sensor, optional
        The cameras' sensor; by default :class:`translucency.rig.shared.sensor.Sensor` with its gain k
        set so that the brightest 0.5 % of the first shot's brightest camera saturate in the long exposure.

    Returns
    -------
    dict
        ``folder``, ``incident`` (vertex indices), ``cameras`` (the true ones), ``seconds``.

    Examples
    --------
    A refusal comes before any render:

    >>> try:
    ...     photograph_object(None, None, "unused", spp=0)
    ... except TranslucencyError as exc:
    ...     print(exc)
    spp: must be >= 1, got 0

    A sphere of skin from three cameras (renders take tens of seconds):

    >>> import tempfile, trimesh
    >>> from pathlib import Path
    >>> from translucency.acquire.mesh import object_volume
    >>> from translucency.rig.object.photographs import photograph_object
    >>> mesh = trimesh.creation.icosphere(subdivisions=2, radius=6.0)
    >>> volume = object_volume("homogeneous:skin1", mesh, 0.5, seed=1)
    >>> folder = Path(tempfile.mkdtemp()) / "sphere-rig"
    >>> out = photograph_object(mesh, volume, folder, n_points=2, n_cameras=3, resolution=(32, 32),
    ...                         spp=4)  # doctest: +SKIP
    >>> sorted(out), len(out["incident"]), len(out["cameras"])  # doctest: +SKIP
    (['cameras', 'folder', 'incident', 'seconds'], 2, 3)
    >>> sorted(p.name for p in folder.glob("*.json"))  # doctest: +SKIP
    ['object.json', 'truth.json']
    """
    t0 = time.perf_counter()
    _refuse_options(image_format, spp, exposures, boundary_eta)
    k_auto, sensor, beam = sensor is None, sensor or Sensor(), beam or LaserBeam()
    volume, spot_radius_mm = _behind_glass(volume, spot_radius_mm, beam, boundary_eta)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    W, H = (int(v) for v in resolution)
    cameras = cameras if cameras is not None else cameras_around(mesh, n_cameras, W, H, seed=seed)
    rng = np.random.default_rng(seed)
    scene = mesh_scene(mesh)
    verts = np.asarray(mesh.vertices, dtype=np.float64)
    # the normals before the export: trimesh writes them into object.ply once computed
    normals = np.asarray(mesh.vertex_normals, dtype=np.float64)
    incident = farthest_points(verts, n_points)
    _write_mesh(folder, mesh)
    cam_entries = _write_cameras(folder, mesh, cameras, sensor, rng, image_format, checkerboards)
    shoot = _Shoot(folder, image_format, exposures, spp, seed, beam, boundary_eta)
    shots = _photograph_shots(
        shoot, mesh, volume, cameras, scene, (verts, normals), incident, sensor, k_auto, cam_entries, progress
    )
    _write_records(folder, volume, boundary_eta, spot_radius_mm, cameras, cam_entries, shots, incident)
    seconds = time.perf_counter() - t0
    return {"folder": str(folder), "incident": incident.tolist(), "cameras": cameras, "seconds": seconds}


@dataclass(frozen=True)
class _Shoot:
    """What every shot of one rig shares: its folder, its files' format, its exposures and its renders."""

    folder: Path
    image_format: str
    exposures: str
    spp: int
    seed: int
    beam: LaserBeam
    eta: float


def _refuse_options(image_format: str, spp: int, exposures: str, boundary_eta: float) -> None:
    """Refuse, before any render, a format, sample count, exposure plan or boundary index out of range."""
    if image_format not in ("pfm", "exr"):
        raise TranslucencyError(f"format: pfm or exr, got {image_format!r}")
    if spp < 1:
        raise TranslucencyError(f"spp: must be >= 1, got {spp}")
    if exposures not in ("brackets", "single"):
        raise TranslucencyError(f"exposures: brackets or single, got {exposures!r}")
    if boundary_eta < 1.0:
        raise TranslucencyError(f"boundary_eta: must be >= 1, got {boundary_eta}")


def _behind_glass(volume, spot_radius_mm: float, beam: LaserBeam, boundary_eta: float):
    """The volume with the boundary's η and the spot radius (mm) widened over the laser's window (η > 1)."""
    if (
        boundary_eta != 1.0
    ):  # behind glass: the window over the laser's disc is the spot the import sets aside
        volume = replace(volume, eta=float(boundary_eta))
        spot_radius_mm = max(spot_radius_mm, 4.0 * beam.radius_mm / 3.0)
    return volume, spot_radius_mm


def _write_mesh(folder: Path, mesh) -> None:
    """Write the object (mm) as ``object.ply``, with whatever per-vertex arrays trimesh has computed."""
    with atomic_path(folder / "object.ply") as tmp:
        mesh.export(tmp, file_type="ply")


def _write_cameras(folder: Path, mesh, cameras, sensor: Sensor, rng, image_format: str, checkerboards: bool):
    """Each camera's folder (dark frame, flat field, checkerboards) and its ``object.json`` entry."""
    cam_entries = []
    for i, c in enumerate(cameras):
        (folder / c.name).mkdir(exist_ok=True)
        dark, flat, _ = sensor.frames((c.height, c.width, 3), seed=i)
        write_hdr(folder / c.name / f"dark.{image_format}", dark)
        write_hdr(folder / c.name / f"flat.{image_format}", flat)
        entry = {
            "name": c.name,
            "width": c.width,
            "height": c.height,
            "pose": {"marks": _marks(mesh, c, rng)},
            "radiometry": {
                "k": sensor.k,
                "dark": f"{c.name}/dark.{image_format}",
                "flat": f"{c.name}/flat.{image_format}",
                "vignetting": list(sensor.vignetting),
                "gain": sensor.gain,
                "read_noise": sensor.read_noise,
                "saturation": sensor.saturation,
            },
        }
        entry["intrinsics"] = _intrinsics(folder, mesh, c, image_format, checkerboards)
        cam_entries.append(entry)
    return cam_entries


def _intrinsics(folder: Path, mesh, c: Camera, image_format: str, checkerboards: bool) -> dict:
    """A camera's intrinsics entry: its checkerboard photographs (written; squares in mm), else K and dist."""
    if not checkerboards:
        return {"K": c.K.tolist(), "dist": c.dist.tolist()}
    names = []
    for b, img in enumerate(render_checkerboards(c, (7, 5), 4.0 * np.linalg.norm(mesh.extents) / 80)):
        name = f"{c.name}/board_{b:02d}.{image_format}"
        write_hdr(folder / name, img)
        names.append(name)
    return {
        "checkerboards": names,
        "inner": [7, 5],
        "square_mm": 4.0 * float(np.linalg.norm(mesh.extents)) / 80,
    }


def _photograph_shots(
    shoot: _Shoot,
    mesh,
    volume,
    cameras,
    scene,
    surface,
    incident,
    sensor: Sensor,
    k_auto,
    cam_entries,
    progress,
) -> list:
    """Render and expose every shot (the first one setting the gain when ``k_auto``); their records."""
    verts, normals = surface  # the mesh's vertices (mm) and their unit normals
    (shoot.folder / "shots").mkdir(exist_ok=True)
    shots = []
    for j, v in enumerate(incident):
        power = 1.0 + 0.1 * np.sin(1.3 * j)  # the laser drifts; a power monitor records it
        radiance = _shot_radiance(shoot, mesh, volume, cameras, scene, verts[v], normals[v], j)
        if k_auto:  # the first shot sets the gain
            sensor = _auto_gain(sensor, radiance, cam_entries)
            k_auto = False
        images = _write_shot(shoot, sensor, cameras, radiance, power, j)
        shots.append({"hit": {"point": verts[v].tolist()}, "power": power, "images": images})
        if progress:
            progress(j + 1, len(incident))
    return shots


def _shot_radiance(shoot: _Shoot, mesh, volume, cameras, scene, point, normal, j: int) -> list:
    """Radiance per W of laser power of shot ``j`` from every camera: one render per repeated frame."""
    repeats = 2 if shoot.exposures == "brackets" else 1
    # repeated frames: two independent renders per camera
    return [
        [
            render_shot(
                mesh,
                volume,
                c,
                point,
                normal,
                shoot.beam,
                spp=shoot.spp,
                seed=shoot.seed * 1000 + 2 * j + rep,
                scene=scene,
                eta=shoot.eta,
            )
            for rep in range(repeats)
        ]
        for c in cameras
    ]


def _auto_gain(sensor: Sensor, radiance: list, cam_entries: list) -> Sensor:
    """The sensor with its gain k set so that the brightest 0.5 % of the brightest camera saturate."""
    top = [float(np.percentile(L[L > 0], 99.5)) for L, *_ in radiance if (L > 0).any()]
    k = 0.8 * sensor.saturation / max(top) if top else sensor.k
    sensor = Sensor(**{**sensor.__dict__, "k": k})
    for entry in cam_entries:
        entry["radiometry"]["k"] = k
    return sensor


def _write_shot(shoot: _Shoot, sensor: Sensor, cameras, radiance: list, power: float, j: int) -> dict:
    """Expose and write shot ``j``'s frames per camera: repeated long ones, a short one with brackets."""
    images = {}
    for i, c in enumerate(cameras):
        frames = []
        noise = shoot.seed * 7919 + 97 * j + 13 * i  # the sensor's noise of this shot and camera
        for rep, L in enumerate(radiance[i]):
            raw = _expose(sensor, L * power, 1.0, noise + 3 * rep, i)
            name = f"shots/{j:03d}_{c.name}_{'ab'[rep]}.{shoot.image_format}"
            write_hdr(shoot.folder / name, raw)
            frames.append({"file": name, "exposure_s": 1.0})
            if rep == 0 and shoot.exposures == "brackets":  # the short exposure, from the same radiance
                raw = _expose(sensor, L * power, SHORT_EXPOSURE, noise + 2, i)
                name = f"shots/{j:03d}_{c.name}_short.{shoot.image_format}"
                write_hdr(shoot.folder / name, raw)
                frames.append({"file": name, "exposure_s": SHORT_EXPOSURE})
        images[c.name] = frames
    return images


def _write_records(
    folder: Path, volume, boundary_eta: float, spot_radius_mm: float, cameras, cam_entries, shots, incident
) -> None:
    """Write ``object.json`` (the lab's hand-over) and ``truth.json`` (the true cameras, for tests)."""
    rig = {
        "format": FORMAT,
        "version": VERSION,
        "mesh": {"file": "object.ply", "scale_mm": 1.0, "up": "z"},
        "boundary": {"eta": float(boundary_eta), "medium_eta": float(volume.eta)},
        "exit_law": "lambertian" if boundary_eta == 1.0 else "dielectric",
        "grazing_deg": 75.0,
        "spot_radius_mm": float(spot_radius_mm),
        "min_coverage": 0.5,
        "max_reprojection_px": 1.0,
        "cameras": cam_entries,
        "shots": shots,
        "sample": {
            "description": dict(volume.description),
            "volume_grid": {"voxel_mm": volume.voxel_mm, "size_mm": list(volume.size_mm)},
        },
    }
    write_json(folder / "object.json", rig)
    write_json(
        folder / "truth.json",
        {"cameras": [dict(c.to_dict(), name=c.name) for c in cameras], "incident": incident.tolist()},
    )


def _expose(
    sensor: Sensor, radiance: np.ndarray, exposure_s: float, seed: int, frames_seed: int
) -> np.ndarray:
    """Raw values of one exposure of ``radiance`` (W mm⁻² sr⁻¹) lasting ``exposure_s`` seconds, by the
    camera whose dark frame and flat field are those of ``frames_seed``."""
    timed = Sensor(**{**sensor.__dict__, "k": sensor.k * exposure_s})
    return timed.expose(radiance, seed=seed, frames_seed=frames_seed)


__all__ = ["LaserBeam", "cameras_around", "render_shot", "photograph_object"]
