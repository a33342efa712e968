"""An object rig's hand-over: the ``object.json`` a lab writes beside its photographs, read and checked.

The file (every path relative to its folder; JSON schema in docs/reference/object-rig.md)::

    {"format": "translucency-object-rig", "version": 1,
     "mesh": {"file": "scan.ply", "scale_mm": 1.0, "up": "z"},
     "boundary": {"eta": 1.0},                      # 1: index-matched; > 1 a smooth dielectric
     "glint_deg": 30,                                # > 1: cameras this close to the mirror direction
                                                     #      set the hit's pixels aside (.glint)
     "exit_law": "lambertian",                       # or "dielectric", "from-views" (.exit_law)
     "grazing_deg": 75, "spot_radius_mm": 0.5, "min_coverage": 0.5, "max_reprojection_px": 1.0,
     "cameras": [{"name": "cam0", "width": 160, "height": 120,
                  "intrinsics": {"K": [[...]], "dist": [...]}       # or {"checkerboards": [files],
                                                                   #     "inner": [7, 5], "square_mm": 4}
                  "pose": {"R": [[...]], "t": [...]}                # or {"rvec": [...], "t": [...]}, or
                                                                   #    {"marks": {"object_mm": [[x, y, z]],
                                                                   #               "image_px": [[u, v]]}}
                  "radiometry": {"k": 5e6, "dark": "cam0/dark.pfm", "flat": "cam0/flat.pfm",
                                 "vignetting": [k1, k2], "gain": 0.01, "read_noise": 0.02,
                                 "saturation": 60.0}}],
     "shots": [{"hit": {"vertex": 12} | {"point": [x, y, z]} | {"ray": {"origin": [...], "direction": [...]}},
                "power": 1.0,
                "images": {"cam0": [{"file": "shots/000_cam0_a.pfm", "exposure_s": 1.0}, ...]}}],
     "sample": {...}}                                # optional: a virtual rig's filling, for its reference

Radiometry (per camera): a raw pixel value Z of a frame of exposure t under laser power P gives the
radiance per unit incident power

    L = (Z − dark) / (k · t · vig(ρ) · flat) / P      [W mm⁻² sr⁻¹ per W]

with ``flat`` normalised here to mean 1 (so k is the value per unit radiance per second of a pixel of
mean response at the image centre) and vig(ρ) = 1 + k1 ρ² + k2 ρ⁴ (ρ from the image centre in
half-diagonals).  The variance of Z is ``gain`` (Z − dark) + ``read_noise``² (photon and read noise).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..._validate import TranslucencyError
from ..shared.hdr import read_hdr
from .cameras import MAX_REPROJECTION_PX, Camera, calibrate_intrinsics, estimate_pose
from .glint import GLINT_DEG

FORMAT = "translucency-object-rig"
VERSION = 1


@dataclass(frozen=True)
class Radiometry:
    """A camera's radiometric calibration (module notes); frames are read where they are used."""

    k: float
    dark: Path | None
    flat: Path | None
    vignetting: tuple = ()
    gain: float = 0.0
    read_noise: float = 0.0
    saturation: float = float("inf")


@dataclass(frozen=True)
class CameraSetup:
    """One camera as the rig file gives it: its size, how to get K and the pose, its radiometry."""

    name: str
    width: int
    height: int
    intrinsics: dict
    pose: dict
    radiometry: Radiometry


@dataclass(frozen=True)
class Exposure:
    file: Path
    exposure_s: float


@dataclass(frozen=True)
class ObjectShot:
    """One laser position: where it hit, its power (W) and each camera's frames."""

    index: int
    hit: dict
    power: float
    frames: dict  # camera name → list of Exposure


@dataclass(frozen=True)
class ObjectRig:
    """A checked ``object.json``.

    Examples
    --------
    The smallest rig file: one camera with K and its pose, one shot; the rest takes its defaults:

    >>> import json, tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> for name in ("scan.ply", "s0.pfm"):  # only their presence is checked here
    ...     _ = (d / name).write_bytes(b"")
    >>> camera = {"name": "cam0", "width": 160, "height": 120, "radiometry": {"k": 5e6},
    ...           "intrinsics": {"K": [[200, 0, 79.5], [0, 200, 59.5], [0, 0, 1]]},
    ...           "pose": {"R": np.eye(3).tolist(), "t": [0, 0, 100]}}
    >>> rig = {"format": "translucency-object-rig", "version": 1, "mesh": {"file": "scan.ply"},
    ...        "cameras": [camera],
    ...        "shots": [{"hit": {"vertex": 12}, "power": 0.5, "images": {"cam0": ["s0.pfm"]}}]}
    >>> _ = (d / "object.json").write_text(json.dumps(rig))
    >>> r = read_object_rig(d / "object.json")
    >>> r.eta, r.exit_law, r.grazing_deg, r.min_coverage, r.scale_mm
    (1.0, 'lambertian', 75.0, 0.5, 1.0)
    >>> r.shots[0].power, r.shots[0].frames["cam0"][0].exposure_s, [p.name for p in r.files]
    (0.5, 1.0, ['scan.ply', 's0.pfm'])
    """

    path: Path
    folder: Path
    mesh_file: Path
    scale_mm: float
    up: str
    eta: float
    exit_law: str
    grazing_deg: float
    spot_radius_mm: float
    glint_deg: float
    min_coverage: float
    max_reprojection_px: float
    cameras: list
    shots: list
    sample: dict | None = None
    raw: dict = field(default_factory=dict)

    @property
    def files(self) -> list[Path]:
        """Every file the import reads (for the provenance and the never-overwrite check)."""
        out = [self.mesh_file]
        for cam in self.cameras:
            out += [p for p in (cam.radiometry.dark, cam.radiometry.flat) if p is not None]
            out += [self.folder / f for f in cam.intrinsics.get("checkerboards", [])]
        for shot in self.shots:
            out += [f.file for frames in shot.frames.values() for f in frames]
        return out


def _number(d: dict, key: str, where: str, default=None, *, positive=False) -> float:
    """The number at ``key`` of a rig file's entry ``where``; faults name the field in backquotes (a rig
    file's field, not a Python argument the command line would translate to a flag)."""
    value = d.get(key, default)
    if value is None:
        raise TranslucencyError(f"{where}: missing `{key}`")
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise TranslucencyError(f"{where}: `{key}` must be a number, got {value!r}") from None
    if not np.isfinite(value) or (positive and value <= 0):
        raise TranslucencyError(f"{where}: `{key}` must be a {'positive' if positive else 'finite'} number")
    return value


def _file(folder: Path, name, where: str) -> Path:
    if not isinstance(name, str) or not name:
        raise TranslucencyError(f"{where}: expected a file name, got {name!r}")
    path = folder / name
    if not path.is_file():
        raise TranslucencyError(f"{where}: {path}: no such file")
    return path


def read_object_rig(path) -> ObjectRig:
    """Read and check ``object.json`` (module notes); every fault is one line naming the entry.

    Parameters
    ----------
    path : str or Path
        The rig file, or the folder holding ``object.json``.

    Returns
    -------
    ObjectRig
        Its files found, its numbers checked (the images themselves are read by the import).

    Raises
    ------
    TranslucencyError
        One line naming the file and the entry at fault.

    Examples
    --------
    >>> import json, tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> for name in ("scan.ply", "s0.pfm"):  # only their presence is checked here
    ...     _ = (d / name).write_bytes(b"")
    >>> camera = {"name": "cam0", "width": 160, "height": 120, "radiometry": {"k": 5e6},
    ...           "intrinsics": {"K": [[200, 0, 79.5], [0, 200, 59.5], [0, 0, 1]]},
    ...           "pose": {"R": np.eye(3).tolist(), "t": [0, 0, 100]}}
    >>> rig = {"format": "translucency-object-rig", "version": 1, "mesh": {"file": "scan.ply"},
    ...        "cameras": [camera],
    ...        "shots": [{"hit": {"vertex": 12}, "power": 0.5, "images": {"cam0": ["s0.pfm"]}}]}
    >>> _ = (d / "object.json").write_text(json.dumps(rig))
    >>> read_object_rig(d).exit_law  # index-matched (eta 1): π L
    'lambertian'
    >>> rig["boundary"] = {"eta": 1.4}
    >>> _ = (d / "object.json").write_text(json.dumps(rig))
    >>> read_object_rig(d).exit_law  # a smooth dielectric: the diffusion law
    'dielectric'
    >>> rig["shots"][0]["images"] = {"cam1": ["s0.pfm"]}
    >>> _ = (d / "object.json").write_text(json.dumps(rig))
    >>> try:
    ...     read_object_rig(d)
    ... except TranslucencyError as exc:
    ...     print(str(exc).split("/")[-1])
    object.json: shot 0: images of unknown camera 'cam1'
    """
    path = _rig_path(path)
    raw = _read_json(path)
    folder = path.parent
    mesh = raw.get("mesh") or {}
    mesh_file = _file(folder, mesh.get("file"), f"{path}: mesh")
    eta = _number(raw.get("boundary") or {}, "eta", f"{path}: boundary", 1.0, positive=True)
    if eta < 1.0:
        raise TranslucencyError(f"{path}: boundary: eta must be >= 1 (the object's index over the air's)")
    cameras = _read_cameras(raw, folder, path)
    shots = _read_shots(raw, folder, path, {c.name for c in cameras})
    # default (measured, docs/validation/object-rig.md, Limits): π L for index-matched, the diffusion law
    # for a dielectric
    law = str(raw.get("exit_law", "dielectric" if eta > 1.0 else "lambertian"))
    return ObjectRig(
        path=path,
        folder=folder,
        mesh_file=mesh_file,
        scale_mm=_number(mesh, "scale_mm", f"{path}: mesh", 1.0, positive=True),
        up=str(mesh.get("up", "z")),
        eta=eta,
        exit_law=law,
        grazing_deg=_number(raw, "grazing_deg", str(path), 75.0, positive=True),
        spot_radius_mm=_number(raw, "spot_radius_mm", str(path), 0.0),
        glint_deg=_number(raw, "glint_deg", str(path), GLINT_DEG if eta > 1.0 else 0.0),
        min_coverage=_number(raw, "min_coverage", str(path), 0.5, positive=True),
        max_reprojection_px=_number(
            raw, "max_reprojection_px", str(path), MAX_REPROJECTION_PX, positive=True
        ),
        cameras=cameras,
        shots=shots,
        sample=raw.get("sample"),
        raw=raw,
    )


def _rig_path(path) -> Path:
    """The rig file: ``path`` itself, or the ``object.json`` in the folder ``path``."""
    path = Path(path)
    if path.is_dir():
        path = path / "object.json"
    return path


def _read_json(path: Path) -> dict:
    """The rig file's JSON, refused unless it reads, parses and names this format and version."""
    try:
        raw = json.loads(path.read_text())
    except OSError as exc:
        raise TranslucencyError(f"{path}: cannot read ({exc.strerror})") from None
    except ValueError as exc:
        raise TranslucencyError(f"{path}: not JSON ({exc})") from None
    if not isinstance(raw, dict) or raw.get("format") != FORMAT or raw.get("version") != VERSION:
        raise TranslucencyError(f"{path}: not an object rig file ({FORMAT} v{VERSION})")
    return raw


def _read_cameras(raw: dict, folder: Path, path: Path) -> list[CameraSetup]:
    """The ``cameras`` entries, checked in order (a non-empty list, no name twice)."""
    cams = raw.get("cameras")
    if not isinstance(cams, list) or not cams:
        raise TranslucencyError(f"{path}: cameras: expected a non-empty list")
    cameras = []
    for i, c in enumerate(cams):
        name = str(c.get("name", f"camera{i}"))
        where = f"{path}: camera {name}"
        if any(cam.name == name for cam in cameras):
            raise TranslucencyError(f"{where}: the name is used twice")
        cameras.append(_read_camera(c, name, folder, where))
    return cameras


def _read_camera(c: dict, name: str, folder: Path, where: str) -> CameraSetup:
    """One camera entry: its intrinsics and pose (as given, files found), radiometry and size (px)."""
    intr, pose, rad = c.get("intrinsics"), c.get("pose"), c.get("radiometry") or {}
    if not isinstance(intr, dict) or not ({"K"} <= intr.keys() or {"checkerboards"} <= intr.keys()):
        raise TranslucencyError(f"{where}: intrinsics: give K (and dist) or checkerboards")
    for f in intr.get("checkerboards", []):
        _file(folder, f, f"{where}: checkerboards")
    if not isinstance(pose, dict) or not ({"t"} <= pose.keys() or {"marks"} <= pose.keys()):
        raise TranslucencyError(f"{where}: pose: give R (or rvec) and t, or marks")
    radiometry = _read_radiometry(rad, folder, where)
    width = int(_number(c, "width", where, positive=True))
    height = int(_number(c, "height", where, positive=True))
    return CameraSetup(name, width, height, intr, pose, radiometry)


def _read_radiometry(rad: dict, folder: Path, where: str) -> Radiometry:
    """A camera's ``radiometry`` entry (module notes): k, its frames' files, vignetting and noise."""
    return Radiometry(
        k=_number(rad, "k", f"{where}: radiometry", positive=True),
        dark=_file(folder, rad["dark"], f"{where}: dark") if rad.get("dark") else None,
        flat=_file(folder, rad["flat"], f"{where}: flat") if rad.get("flat") else None,
        vignetting=tuple(float(v) for v in rad.get("vignetting", ())),
        gain=_number(rad, "gain", f"{where}: radiometry", 0.0),
        read_noise=_number(rad, "read_noise", f"{where}: radiometry", 0.0),
        saturation=_number(rad, "saturation", f"{where}: radiometry", float("inf"), positive=True)
        if rad.get("saturation") is not None
        else float("inf"),
    )


def _read_shots(raw: dict, folder: Path, path: Path, names: set) -> list[ObjectShot]:
    """The ``shots`` entries, checked in order: each hit, laser power and frames of known cameras."""
    shots_raw = raw.get("shots")
    if not isinstance(shots_raw, list) or not shots_raw:
        raise TranslucencyError(f"{path}: shots: expected a non-empty list")
    shots = []
    for j, s in enumerate(shots_raw):
        where = f"{path}: shot {j}"
        hit = s.get("hit")
        if not isinstance(hit, dict) or len(hit.keys() & {"vertex", "point", "ray"}) != 1:
            raise TranslucencyError(f"{where}: hit: give exactly one of vertex, point or ray")
        power = _number(s, "power", where, positive=True)
        images = s.get("images")
        if not isinstance(images, dict) or not images:
            raise TranslucencyError(f"{where}: images: expected {{camera: [frames]}}")
        unknown = images.keys() - names
        if unknown:
            raise TranslucencyError(f"{where}: images of unknown camera {sorted(unknown)[0]!r}")
        frames = {cam: _read_frames(lst, folder, f"{where}: camera {cam}") for cam, lst in images.items()}
        shots.append(ObjectShot(j, hit, power, frames))
    return shots


def _read_frames(lst, folder: Path, where: str) -> list[Exposure]:
    """A camera's frames of one shot: files (found) or ``{"file", "exposure_s"}`` (s; default 1)."""
    if not isinstance(lst, list) or not lst:
        raise TranslucencyError(f"{where}: expected a list of frames")
    return [
        Exposure(
            _file(folder, f.get("file") if isinstance(f, dict) else f, where),
            _number(f, "exposure_s", where, 1.0, positive=True) if isinstance(f, dict) else 1.0,
        )
        for f in lst
    ]


def calibrated_camera(setup: CameraSetup, folder: Path, max_rms_px: float) -> Camera:
    """The camera of a rig entry: K given or by ``cv2.calibrateCamera`` from its checkerboards, the pose
    given or by ``cv2.solvePnP`` from its marks; each refused above ``max_rms_px`` (px rms)."""
    intr, pose, report = setup.intrinsics, setup.pose, {}
    if "K" in intr:
        K, dist = intr["K"], intr.get("dist")
    else:
        images = [read_hdr(folder / f) for f in intr["checkerboards"]]
        for f, im in zip(intr["checkerboards"], images):
            if im.shape[:2] != (setup.height, setup.width):
                raise TranslucencyError(
                    f"{setup.name}: checkerboard {f} is {im.shape[1]} x {im.shape[0]} px, the camera "
                    f"{setup.width} x {setup.height}"
                )
        K, dist, rms = calibrate_intrinsics(
            images,
            tuple(intr.get("inner", (7, 5))),
            float(intr.get("square_mm", 1.0)),
            name=setup.name,
            max_rms_px=max_rms_px,
        )
        report["intrinsics"] = rms
    if "marks" in pose:
        marks = pose["marks"]
        base = Camera(K, dist, np.eye(3), [0.0, 0.0, 1.0], setup.width, setup.height, setup.name)
        cam, rms = estimate_pose(base, marks.get("object_mm"), marks.get("image_px"), max_rms_px=max_rms_px)
        report["pose"] = rms
    else:
        spec = {"K": K, "dist": dist, "width": setup.width, "height": setup.height, **pose}
        cam = Camera.from_dict(spec, setup.name)
    return Camera(cam.K, cam.dist, cam.R, cam.t, cam.width, cam.height, setup.name, report)


__all__ = [
    "ObjectRig",
    "CameraSetup",
    "ObjectShot",
    "Exposure",
    "Radiometry",
    "read_object_rig",
    "calibrated_camera",
]
