r"""A second generator of a lab's object photographs, sharing no code with the virtual rig (issue 35).

The virtual rig (:mod:`translucency.rig.object.photographs`) renders its photographs with Mitsuba's
``volpath`` and its own laser, camera and sensor models.  This one knows nothing of them: it takes the
**photon walks' exits** of a tally (:func:`translucency.acquire.mesh_walk.mesh_random_walk`, the same
transport as ``acquire mesh``, its own seed) and **splats** each exit into every camera that sees it,
through a plain pinhole written here, with a **Lambertian exit law** it knows exactly:

    an exit of weight w (W, per W of laser power) at y, on a face of normal n, seen by a camera at c
    at distance d = |c − y| with μ = n · (c − y)/d > 0, adds to the pixel its projection falls in

        ΔL = w μ / (π Ω_p d²)            [W mm⁻² sr⁻¹ per W]

because a pixel reads the mean radiance over its footprint A_f = Ω_p d² / μ and a Lambertian
exitance M has radiance M / π.  Ω_p is the pixel's solid angle, cos³θ / (f_x f_y) for a pinhole.

Visibility is its own exact ray test: each triangle's projected bounding box binned at ``BIN_SUB`` ×
``BIN_SUB`` bins a pixel, and an exit that faces the camera is seen unless the ray from it to the
camera meets a triangle of its bin more than ``DEPTH_TOL_MM`` in front of it.  (A z-buffer of the
nearest triangle at each sample, extended to its plane, hid 4–14 % of the visible exits near an ear: on
a scan finer than the samples a neighbouring face's plane on a convex part lies in front of the exit,
and a triangle smaller than a sample is nobody's nearest.)
The sensor is its own too: Z = k t vig(ρ) flat L P + dark, with photon (Poisson,
``ELECTRONS_AT_FULL`` at saturation) and read noise, clipped at ``SATURATION``; one exposure a shot set
so that the spot clips, or brackets.  Frames are written by its own PFM writer.

What it writes, the hand-over a lab would give (``object.json``, ``scan.ply``, the frames, dark and
flat fields) plus ``truth.npz``: the exits' own tally (R_d per incident vertex, mm⁻² per W, shared
among vertices by barycentric weight and divided by the vertex's area, as ``acquire mesh`` counts)
and the incident vertices — the exact answer for the sample the photographs were made from.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from translucency.acquire.mesh_walk import EXIT, mesh_random_walk
from translucency.mitsuba import mesh_scene, rays

BIN_SUB = 4  # bins of the visibility test a pixel side
CONE_DEG = 20.0  # exit_law="walk": the cone about the direction to a camera an exit must leave within
DEPTH_TOL_MM = 0.05  # a triangle met this close to an exit, along its ray to the camera, does not hide it
SATURATION = 60.0  # raw value where the sensor clips
ELECTRONS_AT_FULL = 20_000.0  # photo-electrons at saturation: gain = SATURATION / ELECTRONS_AT_FULL
READ_NOISE = 0.01  # raw units
BRACKET = 50.0  # the short frame of a bracket: this many times shorter
DARK = 0.6  # raw units, with a fixed pattern of ±10 %
VIGNETTING = (-0.08, 0.0)  # k1, k2 of vig(ρ) = 1 + k1 ρ² + k2 ρ⁴, ρ in half-diagonals


@dataclass(frozen=True)
class Pinhole:
    """An OpenCV pinhole without distortion: x_c = R X + t; (u, v) = (f x/z + c_x, f y/z + c_y)."""

    name: str
    width: int
    height: int
    K: np.ndarray
    R: np.ndarray
    t: np.ndarray

    @property
    def centre(self) -> np.ndarray:
        return -self.R.T @ self.t

    def project(self, X: np.ndarray):
        """(u, v, z): pixel coordinates (integer = a pixel's centre) and depth along the axis, mm."""
        x = X @ self.R.T + self.t
        z = x[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            u = self.K[0, 0] * x[:, 0] / z + self.K[0, 2]
            v = self.K[1, 1] * x[:, 1] / z + self.K[1, 2]
        return u, v, z

    def pixel_solid_angle(self) -> np.ndarray:
        """Ω_p (H, W), sr: cos³θ / (f_x f_y) at each pixel's centre."""
        fx, fy, cx, cy = self.K[0, 0], self.K[1, 1], self.K[0, 2], self.K[1, 2]
        v, u = np.mgrid[0 : self.height, 0 : self.width].astype(np.float64)
        cos = 1.0 / np.sqrt(1.0 + ((u - cx) / fx) ** 2 + ((v - cy) / fy) ** 2)
        return cos**3 / (fx * fy)


def cameras_on_sphere(mesh, n: int, width: int, height: int, *, seed: int = 0, fill: float = 0.8) -> list:
    """``n`` pinholes on a sphere around the mesh (golden-angle directions turned by ``seed``), each
    aimed at the bounding box's centre, its bounding sphere filling ``fill`` of the narrower half-field
    from three radii away."""
    lo, hi = np.asarray(mesh.bounds, dtype=np.float64)
    centre, radius = 0.5 * (lo + hi), 0.5 * float(np.linalg.norm(hi - lo))
    dist = 3.0 * radius
    f = fill * 0.5 * min(width, height) * dist / radius  # the sphere's radius spans fill × half the field
    K = np.array([[f, 0, (width - 1) / 2], [0, f, (height - 1) / 2], [0, 0, 1.0]])
    rng = np.random.default_rng(seed)
    turn = rng.uniform(0, 2 * np.pi)
    cams = []
    for i in range(n):
        z = 0.85 * (1 - 2 * (i + 0.5) / n)  # stay off the poles, where "up" is undefined
        phi = i * np.pi * (3 - 5**0.5) + turn
        d = np.array([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z])
        C = centre + dist * d
        ez = (centre - C) / np.linalg.norm(centre - C)  # optical axis
        up = np.array([0.0, 0.0, 1.0])
        ey = -(up - (up @ ez) * ez)  # image y points down
        ey /= np.linalg.norm(ey)
        ex = np.cross(ey, ez)  # right-handed: x = y × z
        R = np.stack([ex, ey, ez])
        cams.append(Pinhole(f"cam{i}", width, height, K, R, -R @ C))
    return cams


def triangle_bins(mesh, cam: Pinhole, sub: int = BIN_SUB):
    """The triangles in front of the camera whose projected bounding box covers each bin of sub × sub a
    pixel: a CSR list, ``(start, faces)`` with bin k's triangles ``faces[start[k]:start[k + 1]]`` and bin
    (i, j) at k = i·W·sub + j, covering pixel coordinates [(j/sub) − ½, ((j + 1)/sub) − ½) (rows alike).

    Every triangle whose projection contains a point of a bin is in that bin's list (the bounding box is
    conservative), however small the triangle: the candidates of an exact ray test.
    """
    V = np.asarray(mesh.vertices, dtype=np.float64)
    F = np.asarray(mesh.faces)
    u, v, z = cam.project(V)
    Hs, Ws = cam.height * sub, cam.width * sub
    us, vs = ((u + 0.5) * sub)[F], ((v + 0.5) * sub)[F]  # (F, 3) in bin units
    front = (z[F] > 1e-6).all(axis=1)
    j0 = np.clip(np.floor(us.min(axis=1)), 0, Ws - 1).astype(np.int64)
    j1 = np.clip(np.floor(us.max(axis=1)), 0, Ws - 1).astype(np.int64)
    i0 = np.clip(np.floor(vs.min(axis=1)), 0, Hs - 1).astype(np.int64)
    i1 = np.clip(np.floor(vs.max(axis=1)), 0, Hs - 1).astype(np.int64)
    on_image = (us.max(axis=1) >= 0) & (us.min(axis=1) < Ws) & (vs.max(axis=1) >= 0) & (vs.min(axis=1) < Hs)
    inside = front & on_image
    keys, faces = [], []
    for f in np.flatnonzero(inside):
        ii, jj = np.mgrid[i0[f] : i1[f] + 1, j0[f] : j1[f] + 1]
        keys.append((ii * Ws + jj).ravel())
        faces.append(np.full(ii.size, f))
    keys, faces = np.concatenate(keys), np.concatenate(faces)
    order = np.argsort(keys, kind="stable")
    start = np.searchsorted(keys[order], np.arange(Hs * Ws + 1))
    return start, faces[order]


def splat_image(mesh, cam: Pinhole, bins, position, face, weight, sub: int = BIN_SUB, direction=None):
    """Radiance (H, W) per W of laser power from exits at ``position`` on ``face`` with a Lambertian law,
    or with ``direction`` (n, 3: each exit's own direction of flight) the walk's own law: an exit adds
    ΔL = w / (Ω'_c Ω_p d²) where its direction lies within θ_c = ``CONE_DEG`` of the direction to the
    camera, nothing elsewhere (a pixel's footprint A_f = Ω_p d²/μ, and L = dΦ / (A_f μ Ω'_c) with
    Ω'_c = π (1 − cos² θ_c) = ∫_cap cos θ dω / μ, which a cap inside the hemisphere holds exactly).

    An exit is seen when the ray from it to the camera meets no triangle of its bin
    (:func:`triangle_bins`; Möller–Trumbore, :func:`_ray_triangle`) more than ``DEPTH_TOL_MM`` in front
    of it.
    """
    start, binned = bins
    V, F = np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces)
    face_normal = np.asarray(mesh.face_normals, dtype=np.float64)[face]
    u, v, z = cam.project(position)
    to_cam = cam.centre - position
    d = np.linalg.norm(to_cam, axis=1)
    mu = np.einsum("ij,ij->i", face_normal, to_cam) / d
    col, row = np.floor(u + 0.5).astype(np.int64), np.floor(v + 0.5).astype(np.int64)
    ok = (z > 0) & (mu > 0) & (col >= 0) & (col < cam.width) & (row >= 0) & (row < cam.height)
    si = np.clip(np.floor((v + 0.5) * sub).astype(np.int64), 0, cam.height * sub - 1)
    sj = np.clip(np.floor((u + 0.5) * sub).astype(np.int64), 0, cam.width * sub - 1)
    k = si * cam.width * sub + sj
    # every (exit, candidate triangle) pair of its bin, tested exactly
    count = np.where(ok, start[k + 1] - start[k], 0)
    exit_of = np.repeat(np.arange(len(position)), count)
    cand = binned[np.repeat(start[k] - np.cumsum(count) + count, count) + np.arange(count.sum())]
    t = _ray_triangle(V, F, cand, position[exit_of], (to_cam / d[:, None])[exit_of])
    blocks = (cand != face[exit_of]) & (t > DEPTH_TOL_MM) & (t < d[exit_of])
    hidden = np.bincount(exit_of[blocks], minlength=len(position)) > 0
    ok &= ~hidden
    omega = cam.pixel_solid_angle()
    L = np.zeros(cam.height * cam.width)
    idx = row[ok] * cam.width + col[ok]
    if direction is None:  # Lambertian: M / π
        np.add.at(L, idx, weight[ok] * mu[ok] / (np.pi * omega.ravel()[idx] * d[ok] ** 2))
    else:  # the exits leaving towards the camera
        cos_c = np.cos(np.radians(CONE_DEG))
        toward = np.einsum("ij,ij->i", direction[ok], to_cam[ok] / d[ok, None]) > cos_c
        omega_c = np.pi * (1 - cos_c**2)  # ∫ cos θ dω over the cap / cos θ_axis: exact for a constant L
        np.add.at(
            L, idx[toward], weight[ok][toward] / (omega_c * omega.ravel()[idx[toward]] * d[ok][toward] ** 2)
        )
    return L.reshape(cam.height, cam.width)


def _ray_triangle(V, F, f, origin, direction):
    """Distance (mm) along each ray origin + t·direction to triangle f (Möller–Trumbore; inf where the ray
    misses it)."""
    a, b, c = (V[F[f, k]] for k in range(3))
    e1, e2 = b - a, c - a
    p = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, p)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = origin - a
        u = np.einsum("ij,ij->i", s, p) * inv
        q = np.cross(s, e1)
        v = np.einsum("ij,ij->i", direction, q) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
    met = (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & np.isfinite(t)
    return np.where(met, t, np.inf)


def write_pfm(path: Path, image: np.ndarray) -> None:
    """A colour PFM (little endian, rows bottom to top, as the format says), written whole then renamed."""
    image = np.asarray(image, dtype="<f4")
    h, w = image.shape[:2]
    tmp = path.with_name(path.name + ".part")
    with open(tmp, "wb") as f:
        f.write(f"PF\n{w} {h}\n-1.0\n".encode("ascii"))
        f.write(np.ascontiguousarray(image[::-1]).tobytes())
    tmp.replace(path)


def exits_tally(mesh, point, face, position, n_points: int) -> np.ndarray:
    """(n_points, V) barycentric shares of the exits per vertex (the count ``acquire mesh`` divides)."""
    V = np.asarray(mesh.vertices, dtype=np.float64)
    tri = np.asarray(mesh.faces)[face]
    a, b, c = V[tri[:, 0]], V[tri[:, 1]], V[tri[:, 2]]
    # barycentric coordinates by sub-areas (the exit lies on its face)
    n = np.cross(b - a, c - a)
    nn = np.einsum("ij,ij->i", n, n)
    la = np.einsum("ij,ij->i", np.cross(c - b, position - b), n) / nn
    lb = np.einsum("ij,ij->i", np.cross(a - c, position - c), n) / nn
    bary = np.clip(np.stack([la, lb, 1 - la - lb], axis=1), 0, None)
    bary /= bary.sum(axis=1, keepdims=True)
    out = np.zeros(n_points * len(V))
    np.add.at(out, (np.asarray(point)[:, None] * len(V) + tri).ravel(), bary.ravel())
    return out.reshape(n_points, len(V))


def fresnel_dielectric(cos_i, eta: float):
    """Unpolarised Fresnel reflectance of light arriving from the air at cos θ_i on a medium of index η."""
    cos_i = np.clip(np.abs(cos_i), 0.0, 1.0)
    sin_t2 = (1.0 - cos_i**2) / eta**2
    cos_t = np.sqrt(np.maximum(1.0 - sin_t2, 0.0))
    r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (r_s**2 + r_p**2)


def glint_image(cam: Pinhole, scene, point, normal, eta: float, alpha: float, toward=None) -> np.ndarray:
    r"""Radiance (H, W) per W of the laser's specular glint: the beam arriving from ``toward`` (unit, toward
    the laser; default the normal) reflected by a GGX boundary of roughness ``alpha`` at ``point``, into the
    pixel the point projects to.

    The spot of area A lit by P reflects :math:`L_o = f\,E` with :math:`E = P/A` and the microfacet BRDF
    :math:`f = F(\omega_o\cdot h)\,D(h)/(4\cos\theta_i\cos\theta_o)` (G = 1); the pixel reads the mean
    over its footprint :math:`\Omega_p d^2/\cos\theta_o`, so
    :math:`\Delta L = P\,F\,D/(4\cos\theta_i\,\Omega_p d^2)`, nothing where the point is hidden.
    """
    L = np.zeros((cam.height, cam.width))
    to_cam = cam.centre - point
    d = float(np.linalg.norm(to_cam))
    w_o = to_cam / d
    cos_o = float(normal @ w_o)
    u, v, z = cam.project(point[None])
    col, row = int(np.floor(u[0] + 0.5)), int(np.floor(v[0] + 0.5))
    if cos_o <= 0 or z[0] <= 0 or not (0 <= col < cam.width and 0 <= row < cam.height):
        return L
    si = scene.ray_intersect(rays((point + 1e-3 * w_o)[None], w_o[None]))
    if bool(np.asarray(si.is_valid())[0]) and float(np.asarray(si.t)[0]) < d:
        return L
    w_i = normal if toward is None else np.asarray(toward, dtype=np.float64)
    h = (w_i + w_o) / np.linalg.norm(w_i + w_o)
    cos_h = float(normal @ h)
    tan2 = (1 - cos_h**2) / cos_h**2
    D = alpha**2 / (np.pi * cos_h**4 * (alpha**2 + tan2) ** 2)  # GGX, ∫ D cos θ_h dω = 1
    F = float(fresnel_dielectric(w_o @ h, eta))
    L[row, col] = F * D / (4 * float(normal @ w_i) * cam.pixel_solid_angle()[row, col] * d**2)
    return L


def aim_point(mesh, vertex: int, w: np.ndarray) -> np.ndarray:
    """Where a laser ray of direction ``w`` aimed at ``vertex`` meets the surface: 2 % of the way from the
    vertex toward the centroid of the face around it that faces the beam most (a ray through a vertex
    exactly may slip between its faces in floating point); the import snaps it back to the vertex."""
    faces = mesh.vertex_faces[vertex]
    faces = faces[faces >= 0]
    f = faces[np.argmin(np.asarray(mesh.face_normals)[faces] @ w)]
    V = np.asarray(mesh.vertices, dtype=np.float64)
    return V[vertex] + 0.02 * (np.asarray(mesh.triangles_center)[f] - V[vertex])


def _sensor_fields(cam: Pinhole, rng):
    """Dark frame (raw) and flat field (mean 1), and vig(ρ) (H, W)."""
    h, w = cam.height, cam.width
    dark = DARK * (1 + 0.1 * rng.uniform(-1, 1, (h, w)))
    flat = 1 + 0.05 * rng.standard_normal((h, w))
    flat /= flat.mean()
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    rho2 = ((u - (w - 1) / 2) ** 2 + (v - (h - 1) / 2) ** 2) / (0.25 * (w * w + h * h))
    vig = 1 + VIGNETTING[0] * rho2 + VIGNETTING[1] * rho2**2
    return dark, flat, vig


def splat_rig(
    mesh,
    volume,
    folder,
    *,
    incident,
    cameras,
    photons: int,
    seed: int = 0,
    exposure: str = "single",
    clip_fraction: float = 0.003,
    exit_law: str = "lambertian",
    eta: float = 1.0,
    glint_alpha: float = 0.1,
    incoming=None,
) -> Path:
    """Write a lab's hand-over for ``mesh`` filled with ``volume`` (index-matched), one shot a vertex
    of ``incident``, photographed by ``cameras`` (:class:`Pinhole`).

    ``eta`` > 1: the object behind a smooth dielectric boundary of that index (``volume.eta`` replaced),
    the walks refracted in and out with Fresnel at every crossing (``exit_law`` must be ``"walk"``: the
    exits' own directions in the air are the law behind the boundary), and each shot's specular glint
    (:func:`glint_image`, a GGX boundary of roughness ``glint_alpha``) added where a camera sees it.
    ``incoming`` (P, 3): each shot's beam direction of flight (unit; default along −n): the walks enter
    along it and the rig file gives the shot as a ray.

    ``exposure="single"``: one frame a shot and camera, its gain set on the first shot so that the
    brightest ``clip_fraction`` of the lit pixels (over every camera) clip — the spot is saturated, as
    in a lab's single exposure.  ``"brackets"``: that frame and a second of 1/:data:`BRACKET` its
    exposure time, in which nothing clips.  ``exit_law="walk"``: each exit seen along its own direction
    of flight (:func:`splat_image`), the angular law of the transport itself, not a Lambertian one.
    """
    if eta != 1.0:
        if exit_law != "walk":
            raise ValueError("eta > 1: exits behind a dielectric are not Lambertian; use exit_law='walk'")
        volume = replace(volume, eta=float(eta))
    folder = Path(folder)
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    incident = np.asarray(incident, dtype=np.int64)
    P = len(incident)
    mesh.export(folder / "scan.ply", file_type="ply")
    scene = mesh_scene(mesh)
    V = np.asarray(mesh.vertices, dtype=np.float64)
    normals = np.asarray(mesh.vertex_normals, dtype=np.float64)
    area = np.zeros(len(V))
    np.add.at(area, np.asarray(mesh.faces).ravel(), np.repeat(np.asarray(mesh.area_faces) / 3, 3))

    # -- the photon walks: exits per shot and channel (power 1 W, weight 1/photons each) ------------
    exits, truth = [], np.zeros((P, len(V), 3))
    for ch in range(3):
        res = mesh_random_walk(
            scene,
            mesh.bounds,
            volume,
            ch,
            V[incident],
            normals[incident],
            photons,
            seed=int(seed) * 31 + 977 * ch + 5,
            index_matched=eta == 1.0,
            reentry=True,  # light crossing the air from one part into another, as a photograph sees it
            incoming=None if incoming is None else np.asarray(incoming, dtype=np.float64),
        )
        point = np.repeat(np.arange(P), photons)
        ok = res.code == EXIT
        flight = res.direction[ok] / np.linalg.norm(res.direction[ok], axis=1, keepdims=True)
        exits.append((point[ok], res.face[ok], res.position[ok].astype(np.float64), flight))
        truth[..., ch] = exits_tally(mesh, point[ok], res.face[ok], exits[-1][2], P) / (photons * area)

    # -- radiance per camera and shot ------------------------------------------------------------------
    radiance = np.zeros((P, len(cameras), cameras[0].height, cameras[0].width, 3))
    for i, cam in enumerate(cameras):
        bins = triangle_bins(mesh, cam)
        for ch, (point, face, pos, flight) in enumerate(exits):
            for j in range(P):
                m = point == j
                radiance[j, i, ..., ch] = splat_image(
                    mesh, cam, bins, pos[m], face[m], np.full(m.sum(), 1 / photons),
                    direction=flight[m] if exit_law == "walk" else None,
                )  # fmt: skip
            if eta != 1.0:  # the glint: the same in every channel (the boundary is grey)
                toward = [None] * P if incoming is None else -np.asarray(incoming, dtype=np.float64)
                radiance[:, i] += np.stack(
                    [
                        glint_image(cam, scene, V[v], normals[v], eta, glint_alpha, toward[j])
                        for j, v in enumerate(incident)
                    ]
                )[..., None]

    # -- the sensor: one exposure of 1 s a shot, the spot clipped --------------------------------------
    rng = np.random.default_rng(10_000 + int(seed))
    lit = radiance[0][radiance[0] > 0]
    k = SATURATION / np.quantile(lit, 1 - clip_fraction)  # raw per (W mm⁻² sr⁻¹) per s
    gain = SATURATION / ELECTRONS_AT_FULL
    power = 1.0 + 0.05 * np.cos(np.arange(P))  # the laser drifts; the power monitor records it
    cam_entries, fields = [], []
    for cam in cameras:
        dark, flat, vig = _sensor_fields(cam, rng)
        fields.append((dark, flat, vig))
        (folder / cam.name).mkdir(exist_ok=True)
        write_pfm(folder / cam.name / "dark.pfm", np.repeat(dark[..., None], 3, axis=2))
        write_pfm(folder / cam.name / "flat.pfm", np.repeat(flat[..., None], 3, axis=2))
        cam_entries.append(
            {
                "name": cam.name,
                "width": cam.width,
                "height": cam.height,
                "intrinsics": {"K": cam.K.tolist(), "dist": [0.0] * 5},
                "pose": {"R": cam.R.tolist(), "t": cam.t.tolist()},
                "radiometry": {
                    "k": float(k),
                    "dark": f"{cam.name}/dark.pfm",
                    "flat": f"{cam.name}/flat.pfm",
                    "vignetting": list(VIGNETTING),
                    "gain": gain,
                    "read_noise": READ_NOISE,
                    "saturation": SATURATION,
                },
            }
        )
    shots = []
    for j in range(P):
        images = {}
        for i, cam in enumerate(cameras):
            dark, flat, vig = fields[i]
            images[cam.name] = []
            for t in (1.0, 1.0 / BRACKET) if exposure == "brackets" else (1.0,):
                signal = k * t * (vig * flat)[..., None] * radiance[j, i] * power[j]  # raw
                electrons = rng.poisson(np.maximum(signal, 0) / gain)
                Z = electrons * gain + dark[..., None] + READ_NOISE * rng.standard_normal(signal.shape)
                Z = np.minimum(Z, SATURATION)
                name = f"frames/{j:03d}_{cam.name}_{t:g}s.pfm"
                write_pfm(folder / name, Z)
                images[cam.name].append({"file": name, "exposure_s": t})
        if incoming is None:
            hit = {"vertex": int(incident[j])}
        else:  # the laser's ray, from 40 mm back along it
            w = np.asarray(incoming[j], dtype=np.float64)
            aim = aim_point(mesh, int(incident[j]), w)
            hit = {"ray": {"origin": (aim - 40.0 * w).tolist(), "direction": w.tolist()}}
        shots.append({"hit": hit, "power": float(power[j]), "images": images})
    rig = {
        "format": "translucency-object-rig",
        "version": 1,
        "mesh": {"file": "scan.ply", "scale_mm": 1.0, "up": "z"},
        "boundary": {"eta": float(eta)},
        "exit_law": "lambertian" if eta == 1.0 else "dielectric",
        "spot_radius_mm": 0.0,
        "cameras": cam_entries,
        "shots": shots,
    }
    np.savez(folder / "truth.npz", R_d=truth, incident=incident, area=area)
    tmp = folder / "object.json.part"
    tmp.write_text(json.dumps(rig, indent=1))
    tmp.replace(folder / "object.json")
    return folder
