"""Virtual photographs of a virtual DISCO sample, rendered by Mitsuba 3: the test rig of the importer.

A slab (:func:`translucency.mitsuba.scenes.slab_scene`, index-matched: Mitsuba cannot pass a delta
light through a smooth dielectric) is lit by a narrow ``spot`` beam straight down at each incident point
and seen by a ``perspective`` camera at a known oblique pose (:class:`VirtualCamera`).  ``volpath``
renders the radiance L per unit intensity of the spot, one grey channel of the volume at a time.  The
sensor model (:class:`translucency.rig.shared.sensor.Sensor`) then turns radiance into raw pixel values:
a gain ``k`` (value per unit radiance), vignetting, pixel response non-uniformity (the flat field), a
dark offset, photon noise (``gain`` values per electron), read noise and clipping at the saturation level.

The camera's plane-to-image homography follows from its pose (:meth:`VirtualCamera.homography`):
with Mitsuba's ``look_at`` frame (left, up, forward) R, focal length f = (W/2)/tan(fov/2) pixels and the
image centre c, ``H = K Rᵀ [e_x, e_y, −o]``, ``K = [[−f, 0, c_u], [0, −f, c_v], [0, 0, 1]]`` (u grows to
the camera's right = −left, v downwards); pixel [row, col] is centred at (u, v) = (col, row).

:func:`photograph_sample` writes what a lab would hand over: a folder of HDR images (PFM or EXR), a
``positions.csv``, a dark frame, a flat field, a photograph of glowing calibration markers and a
``calibration.json`` with the marked points.  Units: mm; the spot's power in W per W/sr of intensity.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..._validate import TranslucencyError
from ...io.atomic import atomic_path, write_json
from ...mitsuba import (
    SPOT_BEAM_FRACTION,
    markers_scene,
    mitsuba,
    perspective_camera_dict,
    slab_scene,
    spot_dict,
)
from ..shared.hdr import write_hdr
from ..shared.homography import Homography, homography_from_points
from ..shared.sensor import Sensor
from ..shared.spot import spot_power
from .calibration import find_markers, match_markers


@dataclass(frozen=True)
class VirtualCamera:
    """A pinhole camera at ``origin`` looking at ``target`` (mm) with a horizontal field of view (degrees).

    Examples
    --------
    Straight above the target with a 90° field: f = 32 px / tan 45°, 16 mm away, so 2 px per mm; the
    plane seen from above is mirrored (det < 0):

    >>> cam = VirtualCamera((5.0, 5.0, 16.0), (5.0, 5.0, 0.0), fov_deg=90.0, width=64, height=64)
    >>> H = cam.homography()
    >>> H.to_image([[5.0, 5.0]]).round(6).tolist()  # the target at the image centre
    [[31.5, 31.5]]
    >>> round(float(H.pixels_per_mm2([[5.0, 5.0]])[0]), 6)
    4.0
    >>> bool(np.linalg.det(H.jacobian([[5.0, 5.0]])[0]) < 0)
    True
    """

    origin: tuple[float, float, float]
    target: tuple[float, float, float]
    fov_deg: float = 36.0
    width: int = 64
    height: int = 64

    def frame(self) -> np.ndarray:
        """Rows left, up, forward of Mitsuba's ``look_at`` (up hint +z off the axis, as scenes.look_at)."""
        o, t = np.asarray(self.origin, float), np.asarray(self.target, float)
        fwd = (t - o) / np.linalg.norm(t - o)
        hint = np.array([0.0, 0.0, 1.0]) if abs(fwd[2]) < 0.99 else np.array([0.0, 1.0, 0.0])
        left = np.cross(hint, fwd)
        left /= np.linalg.norm(left)
        return np.stack([left, np.cross(fwd, left), fwd])

    def homography(self) -> Homography:
        """The plane z = 0 → image homography of this pose (see the module's notes).

        Examples
        --------
        >>> cam = VirtualCamera((5.0, 5.0, 20.0), (5.0, 5.0, 0.0), 40.0, 64, 64)
        >>> np.round(cam.homography().to_image([[5.0, 5.0]]), 6).tolist()
        [[31.5, 31.5]]
        """
        R = self.frame()
        f = 0.5 * self.width / np.tan(np.radians(self.fov_deg) / 2)
        K = np.array([[-f, 0, 0.5 * self.width - 0.5], [0, -f, 0.5 * self.height - 0.5], [0, 0, 1.0]])
        o = np.asarray(self.origin, float)
        M = K @ np.column_stack([R[:, 0], R[:, 1], -R @ o])
        return Homography.from_matrix(M, "camera pose")

    def sensor_dict(self, spp: int) -> dict:
        return perspective_camera_dict(self.origin, self.target, self.fov_deg, self.width, self.height, spp)


@dataclass(frozen=True)
class Beam:
    """The laser of the virtual rig: a spot at ``distance_mm`` above the point, lighting a disc of
    ``radius_mm`` (Mitsuba's linear fall-off from :data:`SPOT_BEAM_FRACTION` of the cutoff).

    Examples
    --------
    A 0.3 mm disc from 50 mm: with a = 0.75 (the fall-off's start) its power per unit intensity is
    close to the cone's solid angle π θ² times (1 + a + a²)/3, and its rms radius close to
    R √(0.3 (1 + a + a² + a³ + a⁴)/(1 + a + a²)) = 0.6291 R (R/√2 = 0.7071 R for a uniform disc):

    >>> b = Beam(radius_mm=0.3, distance_mm=50.0)
    >>> theta = float(np.radians(b.cutoff_deg))
    >>> round(b.cutoff_deg, 4), round(b.power() / (np.pi * theta**2), 4), round(b.rms_mm() / 0.3, 4)
    (0.3438, 0.7708, 0.6291)
    """

    radius_mm: float = 0.3
    distance_mm: float = 50.0

    @property
    def cutoff_deg(self) -> float:
        return float(np.degrees(np.arctan(self.radius_mm / self.distance_mm)))

    def rms_mm(self) -> float:
        """√⟨ρ²⟩ of the irradiance the beam puts on the sample, mm (for ``ImportSetup.beam_rms``):
        ρ = d tan θ, irradiance ∝ f(θ) cos³θ (the spot's fall-off f, the inverse square and the slant)."""
        tc = np.radians(self.cutoff_deg)
        tw = SPOT_BEAM_FRACTION * tc
        th = np.linspace(0.0, tc, 20001)
        f = np.where(th <= tw, 1.0, (tc - th) / (tc - tw)) * np.cos(th) ** 3
        rho = self.distance_mm * np.tan(th)
        area = rho * np.gradient(rho, th)  # ρ dρ/dθ: the plane's area element per dθ (× 2π)
        return float(np.sqrt(np.trapezoid(f * rho**2 * area, th) / np.trapezoid(f * area, th)))

    def power(self) -> float:
        """Power (W) per unit intensity (W/sr): 2π ∫ f(θ) sin θ dθ over the cone, in float64."""
        return spot_power(self.cutoff_deg)

    def emitter_dict(self, x: float, y: float) -> dict:
        return spot_dict((x, y, self.distance_mm), (x, y, 0.0), self.cutoff_deg, 1.0, up=(0.0, 1.0, 0.0))


def render_radiance(
    volume, camera: VirtualCamera, beam: Beam, x_i, *, spp: int = 64, seed: int = 0, channels=(0, 1, 2)
):
    """Radiance (H, W, 3) per unit spot intensity of the slab lit at ``x_i``, one ``volpath`` render per
    channel in ``channels`` (the others copy the last rendered: for grey volumes, render one)."""
    mi = mitsuba()
    out = np.zeros((camera.height, camera.width, 3), np.float32)
    for c in range(3):
        if c not in channels:
            out[..., c] = out[..., c - 1]
            continue
        emitter = beam.emitter_dict(float(x_i[0]), float(x_i[1]))
        scene = slab_scene(volume, c, emitter, camera.sensor_dict(spp))
        out[..., c] = np.array(mi.render(scene, spp=int(spp), seed=3 * int(seed) + c))[..., 0]
    return out


def render_markers(camera: VirtualCamera, markers_mm, radius_mm: float = 0.25, spp: int = 16) -> np.ndarray:
    """A photograph (H, W, 3) of glowing disc markers at ``markers_mm`` (N, 2) on the plane z = 0."""
    scene = markers_scene(camera.sensor_dict(spp), markers_mm, radius_mm)
    return np.array(mitsuba().render(scene, spp=int(spp), seed=0), dtype=np.float32)


def photograph_sample(
    volume,
    x_i,
    folder,
    *,
    camera: VirtualCamera,
    beam: Beam | None = None,
    sensor: Sensor | None = None,
    spp: int = 64,
    seed: int = 0,
    channels=(0, 1, 2),
    image_format: str = "pfm",
    markers_mm=None,
    scale=None,
    reference: dict | None = None,
) -> dict:
    """Photograph ``volume`` lit at each of ``x_i`` (P, 2) and write a lab's hand-over into ``folder``.

    Files: ``shot_NNN.pfm|exr`` (raw pixel values), ``positions.csv`` (file, x, y, power),
    ``dark.pfm``, ``flat.pfm``, ``markers.pfm`` and ``calibration.json`` (marked points found in the marker
    photograph, the dark and flat frames, vignetting, noise model, saturation and — if given — the
    radiometric ``scale``, or a ``reference``: {"volume", "x" (mm), "radius_mm", "total" (its known
    reflectance within that radius, R, G, B), "exposure_s", optional "inner_mm" (the total is over the
    annulus from there) and "spp" (samples per pixel of its photograph)} photographed into
    ``reference.pfm``).

    Parameters
    ----------
    volume : Volume
        The sample (a slab, index-matched).
    x_i : array (P, 2)
        Incident points, mm.
    folder : str or Path
        Where the hand-over goes (created).
    camera : VirtualCamera
        The camera's pose and image size.
    beam : Beam, optional
        The laser (default :class:`Beam`).
    sensor : Sensor, optional
        Radiance → raw values (default :class:`~translucency.rig.shared.sensor.Sensor`).
    spp : int
        Samples per pixel of each render.
    seed : int
        The renders' and the sensor's noise.
    channels : tuple of int
        The channels rendered (a grey volume needs one; the others copy it).
    image_format : {"pfm", "exr"}
        The shots' file format.
    markers_mm : array (N, 2), optional
        The calibration markers (default: eight on an ellipse the camera sees whole).
    scale, reference : optional
        The radiometric scale written to ``calibration.json``, or a reference to photograph (above).

    Returns
    -------
    dict
        ``homography`` (the true one, from the pose), ``marked`` (estimated one), ``rms_px``, ``power``.

    Examples
    --------
    A refusal comes before any render:

    >>> from translucency import TranslucencyError
    >>> from translucency.rig.planar.photographs import VirtualCamera, photograph_sample
    >>> cam = VirtualCamera((6.0, -3.0, 11.0), (6.0, 6.0, 0.0), 40.0, 32, 32)
    >>> try:
    ...     photograph_sample(None, [[6.0, 6.0]], "unused", camera=cam, image_format="png")
    ... except TranslucencyError as exc:
    ...     print(exc)
    format: pfm or exr, got 'png'

    Two shots of a homogeneous slab (renders take seconds):

    >>> import tempfile
    >>> from pathlib import Path
    >>> from translucency.acquire import Volume
    >>> vol = Volume.homogeneous((8, 48, 48), 0.25, (1.0, 0.8, 0.6), (0.01, 0.02, 0.04))
    >>> folder = Path(tempfile.mkdtemp())
    >>> out = photograph_sample(vol, [[6.0, 6.0], [5.0, 6.0]], folder, camera=cam, spp=4,
    ...                         scale=5e6)
    >>> sorted(out), round(out["power"] * 1e5, 4)
    (['homography', 'marked', 'power', 'rms_px'], 8.7177)
    >>> sorted(p.name for p in folder.iterdir())  # doctest: +NORMALIZE_WHITESPACE
    ['calibration.json', 'dark.pfm', 'flat.pfm', 'markers.pfm', 'positions.csv',
     'shot_000.pfm', 'shot_001.pfm']
    """
    beam = beam or Beam()
    sensor = sensor or Sensor()
    if image_format not in ("pfm", "exr"):
        raise TranslucencyError(f"format: pfm or exr, got {image_format!r}")
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    x_i = np.asarray(x_i, float).reshape(-1, 2)
    power = beam.power()
    rows = _write_shots(volume, x_i, folder, camera, beam, sensor, spp, seed, channels, image_format, power)
    _write_positions(folder, rows)
    dark, flat, _ = sensor.frames((camera.height, camera.width, 3))
    write_hdr(folder / "dark.pfm", dark)
    write_hdr(folder / "flat.pfm", flat)
    if markers_mm is None:
        markers_mm = default_markers(x_i, camera)
    photo = render_markers(camera, markers_mm)
    write_hdr(folder / "markers.pfm", photo)
    truth = camera.homography()
    found = match_markers(markers_mm, find_markers(photo, len(markers_mm)), truth)
    est, rms = homography_from_points(markers_mm, found)
    calib = _calibration(sensor, markers_mm, found)
    if scale is not None:
        calib["scale"] = np.asarray(scale).tolist()
    if reference is not None:  # a photograph of a reference of known reflectance, at a shorter exposure
        calib["reference"] = _write_reference(
            folder, reference, camera, beam, sensor, spp, seed, channels, power
        )
    write_json(folder / "calibration.json", calib)
    return {"homography": truth, "marked": est, "rms_px": rms, "power": power}


def _write_shots(volume, x_i, folder: Path, camera, beam, sensor, spp, seed, channels, image_format, power):
    """Render, expose and write a shot per incident point; the rows of ``positions.csv`` (mm, W)."""
    rows = []
    for j, p in enumerate(x_i):
        L = render_radiance(volume, camera, beam, p, spp=spp, seed=seed + j, channels=channels)
        raw = sensor.expose(L, seed=1000 + seed + j)
        name = f"shot_{j:03d}.{image_format}"
        write_hdr(folder / name, raw)
        rows.append({"file": name, "x": f"{p[0]:.6f}", "y": f"{p[1]:.6f}", "power": f"{power:.9g}"})
    return rows


def _write_positions(folder: Path, rows: list) -> None:
    """Write ``positions.csv``: each shot's file, incident point (mm) and laser power (W)."""
    with atomic_path(folder / "positions.csv") as tmp:
        with open(tmp, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=["file", "x", "y", "power"])
            w.writeheader()
            w.writerows(rows)


def _calibration(sensor: Sensor, markers_mm, found) -> dict:
    """``calibration.json``'s marked points (mm, px), dark and flat frames and the sensor's noise model."""
    return {
        "points": {"sample_mm": np.asarray(markers_mm).tolist(), "image_px": found.tolist()},
        "dark": "dark.pfm",
        "flat": "flat.pfm",
        "vignetting": list(sensor.vignetting),
        "gain": sensor.gain,
        "read_noise": sensor.read_noise,
        "saturation": sensor.saturation,
    }


def _write_reference(folder: Path, reference: dict, camera, beam, sensor, spp, seed, channels, power) -> dict:
    """Photograph the reference at its exposure (s) into ``reference.pfm``; its calibration entry."""
    t = float(reference.get("exposure_s", 0.1))
    ref_spp = int(reference.get("spp", spp))  # one image sets every shot's scale: worth more samples
    L = render_radiance(
        reference["volume"], camera, beam, reference["x"], spp=ref_spp, seed=seed + 999, channels=channels
    )
    ref_sensor = Sensor(**{**sensor.__dict__, "k": sensor.k * t})
    write_hdr(folder / "reference.pfm", ref_sensor.expose(L, seed=seed + 4242))
    return {
        "image": "reference.pfm",
        "x": float(reference["x"][0]),
        "y": float(reference["x"][1]),
        "radius_mm": float(reference["radius_mm"]),
        "inner_mm": float(reference.get("inner_mm", 0.0)),
        "total": np.asarray(reference["total"], float).tolist(),
        "power": power,
        "exposure_s": t,
    }


def default_markers(x_i, camera: VirtualCamera, margin_px: float = 4.0) -> np.ndarray:
    """Eight markers on an ellipse around the incident points, as wide as the camera sees them whole."""
    c = np.asarray(x_i, float).reshape(-1, 2).mean(axis=0)
    a = np.radians(np.arange(8) * 45.0 + 10.0)
    H = camera.homography()
    for r in np.linspace(20.0, 0.5, 200):  # mm, shrinking until every marker is inside the picture
        m = np.stack([c[0] + r * np.cos(a), c[1] + 0.8 * r * np.sin(a)], axis=1)
        uv = H.to_image(m)
        lo, hi = margin_px, np.array([camera.width, camera.height]) - 1 - margin_px
        if np.all((uv >= lo) & (uv <= hi)):
            return m
    raise TranslucencyError("markers: the camera does not see the incident points")


def homography_error(estimated: Homography, truth: Homography, xy) -> float:
    """Largest image distance (pixels) between the two homographies' images of sample points ``xy``."""
    return float(np.max(np.linalg.norm(estimated.to_image(xy) - truth.to_image(xy), axis=1)))


__all__ = [
    "VirtualCamera",
    "Beam",
    "render_radiance",
    "render_markers",
    "photograph_sample",
    "default_markers",
    "homography_error",
]
