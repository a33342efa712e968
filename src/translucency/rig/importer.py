"""Photographs of a scanned laser spot → a planar data set (the same format as ``acquire planar``).

For each laser position (incident point x_i) the rig provides one HDR image (or several repeated
frames, or a bracket of LDR exposures).  Each image becomes one window of R_d on the sample-plane
grid around x_i:

1. **read** the image(s) (:mod:`.hdr`); repeated frames are averaged, brackets merged;
2. **correct** in the image: subtract the dark frame, divide by the flat field and the vignetting
   fall-off, divide by the exposure time (s) and the laser power (W);
3. **resample** to the window's pixels on the sample plane: each output pixel is the mean over
   s × s points spread evenly over its area *on the sample* (so the mean is area-weighted there), each
   point read bilinearly at its image position H·(x, y, 1); a ``flux`` camera's values are first
   multiplied by the area Jacobian |det ∂(u, v)/∂(x, y)| (pixels per mm²) so that they become a density;
4. **scale** by the calibration's radiometric scale (pixel value per unit exitance):
   R_d = value / (scale · power · exposure), in mm⁻².

The **variance** follows the stated noise model of the sensor, Var = gain · value + read_noise² per raw
frame (or, with repeated frames, their spread / n), carried through the same corrections; the mean of
s × s interpolated values of n_eff independent image pixels has variance ≈ mean Var / max(1, n_eff),
n_eff = pitch² · pixels per mm².

The **mask** drops window pixels that touch (through their bilinear footprint) an image pixel that is
saturated (at or above the calibration's ``saturation`` in any channel, grown by ``dilate`` pixels for
blooming), under-exposed (below ``floor`` after the dark frame, or in no exposure of a bracket), not
finite, outside the image, or within ``specular_radius`` mm of x_i (the laser's direct reflection and
the blinding entry spot).

Work runs in chunks of points with the data set's ``chunk_done`` flags: a re-run with the same inputs
(file hashes included) resumes; other inputs are refused without ``overwrite``.
"""

from __future__ import annotations

import csv
import hashlib
import json
import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from scipy.ndimage import binary_dilation

from .._validate import TranslucencyError
from .._version import __version__
from ..cluster import open_cluster, parse_scheduler
from ..fit._varpro import fit_exponentials_batched
from ..io.dataset import FORMAT, VERSION, PlanarDataset, create_dataset
from ..io.outputs import output_lock
from .calibration import Calibration
from .hdr import HDR_SUFFIXES, LDR_SUFFIXES, merge_exposures, read_hdr, read_ldr

IMAGE_SUFFIXES = HDR_SUFFIXES + LDR_SUFFIXES


@dataclass(frozen=True)
class Shot:
    """One laser position: its image file(s), where the laser is, its power and exposure time(s)."""

    files: tuple[Path, ...]
    position: tuple[float, float]
    units: str  # "mm" (sample) or "px" (image)
    power: float = 1.0
    exposures: tuple[float, ...] = (1.0,)


@dataclass(frozen=True)
class ImportSetup:
    """Arguments of an import (lengths in mm).

    ``pitch``: output pixel; ``window``: window side (odd number of pixels, x_i in the centre one);
    ``supersample``: points per output pixel side (at least, raised to one per image pixel);
    ``specular_radius``: mask around x_i; ``dilate``:
    growth of the saturated mask, image pixels; ``floor``: values below it (after the dark frame) are
    under-exposed; ``sample_size``: (W, H) of the sample, pixels outside are masked (optional).
    """

    pitch: float = 0.25
    window: float = 8.0
    supersample: int = 3
    specular_radius: float = 0.0
    dilate: int = 1
    floor: float | None = None
    sample_size: tuple[float, float] | None = None
    eta: float = 1.3
    chunk_points: int = 16
    dtype: str = "float32"
    beam_rms: float = 0.0  # √⟨ρ²⟩ of the beam's irradiance on the sample, mm: 0 = a pencil beam

    def check(self) -> None:
        if not (np.isfinite(self.pitch) and self.pitch > 0):
            raise TranslucencyError(f"pitch: must be a positive length in mm, got {self.pitch}")
        if not (np.isfinite(self.window) and self.window >= self.pitch):
            raise TranslucencyError(
                f"window: must be at least one pixel ({self.pitch} mm), got {self.window}"
            )
        if not 1 <= int(self.supersample) <= 16:
            raise TranslucencyError(f"supersample: must lie in 1..16, got {self.supersample}")
        if not self.specular_radius >= 0 or not self.dilate >= 0:
            raise TranslucencyError("specular radius and dilate: must be >= 0")
        if self.chunk_points < 1:
            raise TranslucencyError(f"chunk: must be >= 1, got {self.chunk_points}")
        if not (np.isfinite(self.beam_rms) and self.beam_rms >= 0):
            raise TranslucencyError(f"beam rms: must be a length >= 0 mm, got {self.beam_rms}")
        if self.dtype not in ("float32", "float16"):
            raise TranslucencyError(f"dtype: expected float32 or float16, got {self.dtype!r}")

    def window_pixels(self) -> int:
        n = max(1, int(round(self.window / self.pitch)))
        return n if n % 2 == 1 else n + 1


# -- the table of laser positions ---------------------------------------------------------------------
def _split(value, name, where) -> list[str]:
    if isinstance(value, list | tuple):
        return [str(v) for v in value]
    return [v.strip() for v in str(value).split(";") if v.strip()] if value not in (None, "") else []


def read_positions(path, folder) -> list[Shot]:
    """The laser positions of a rig: a CSV or JSON table.

    Columns (CSV header, or keys of each JSON object in a list, or under ``"points"``):
    ``x``, ``y`` (sample mm) **or** ``u``, ``v`` (image pixels); optional ``file`` (image file(s) in
    ``folder``, several separated by ``;`` — repeated frames, or a bracket when ``exposure`` lists one
    time per file), ``power`` (W, for normalisation; default 1), ``exposure`` (s; default 1).  Without a
    ``file`` column the images of ``folder`` are taken in sorted order, one per row.

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / "a.pfm").write_bytes(b"")
    >>> _ = (d / "pos.csv").write_text("file,x,y,power\\na.pfm,1.5,2.0,0.5\\n")
    >>> s = read_positions(d / "pos.csv", d)[0]
    >>> s.files[0].name, s.position, s.units, s.power
    ('a.pfm', (1.5, 2.0), 'mm', 0.5)
    """
    path, folder = Path(path), Path(folder)
    if not path.is_file():
        raise TranslucencyError(f"{path}: no such table of laser positions")
    if not folder.is_dir():
        raise TranslucencyError(f"{folder}: no such folder of images")
    try:
        if path.suffix.lower() == ".json":
            obj = json.loads(path.read_text())
            rows = obj.get("points") if isinstance(obj, dict) else obj
            if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
                raise TranslucencyError(f"{path}: expected a list of objects (or one under 'points')")
        else:
            with open(path, newline="") as f:
                rows = [{k.strip().lower(): v for k, v in r.items() if k} for r in csv.DictReader(f)]
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise TranslucencyError(f"{path}: not a readable table ({type(exc).__name__})") from None
    if not rows:
        raise TranslucencyError(f"{path}: no laser positions")
    keys = set(rows[0])
    if {"x", "y"} <= keys:
        units, cols = "mm", ("x", "y")
    elif {"u", "v"} <= keys:
        units, cols = "px", ("u", "v")
    else:
        raise TranslucencyError(f"{path}: needs columns x, y (mm) or u, v (pixels); has {sorted(keys)}")
    if "file" in keys:
        names = [_split(r.get("file"), "file", path) for r in rows]
    else:
        found = sorted(p.name for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
        if len(found) != len(rows):
            raise TranslucencyError(
                f"{path}: {len(rows)} laser positions but {len(found)} images in {folder}; "
                "the counts must match (or name each row's image in a 'file' column)"
            )
        names = [[n] for n in found]
    shots = []
    for i, (r, files) in enumerate(zip(rows, names)):
        where = f"{path}, row {i + 1}"
        try:
            pos = tuple(float(r[c]) for c in cols)
            power = float(r.get("power") or 1.0)
            times = [float(t) for t in _split(r.get("exposure"), "exposure", where)] or [1.0]
        except (TypeError, ValueError):
            raise TranslucencyError(f"{where}: position, power and exposure must be numbers") from None
        if not files:
            raise TranslucencyError(f"{where}: no image file named")
        if not np.all(np.isfinite(pos)):
            raise TranslucencyError(f"{where}: position {pos} is not finite")
        if not (np.isfinite(power) and power > 0):
            raise TranslucencyError(f"{where}: power must be > 0 W, got {power}")
        if not all(np.isfinite(t) and t > 0 for t in times):
            raise TranslucencyError(f"{where}: exposure times must be > 0 s, got {times}")
        if len(times) not in (1, len(files)):
            raise TranslucencyError(f"{where}: {len(files)} images but {len(times)} exposure times")
        paths = tuple(folder / n for n in files)
        for p in paths:
            if not p.is_file():
                raise TranslucencyError(f"{where}: image {p} is missing")
            if p.suffix.lower() not in IMAGE_SUFFIXES:
                raise TranslucencyError(f"{where}: {p.name} is not an image ({', '.join(IMAGE_SUFFIXES)})")
        ldr = [p.suffix.lower() in LDR_SUFFIXES for p in paths]
        if any(ldr) and not all(ldr):
            raise TranslucencyError(f"{where}: mixes HDR and LDR images")
        if all(ldr) and len(paths) > 1 and len(times) != len(paths):
            raise TranslucencyError(f"{where}: a bracket of {len(paths)} LDR images needs as many exposures")
        shots.append(Shot(paths, pos, units, power, tuple(times)))
    return shots


def sha256_file(path, block: int = 1 << 22) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while chunk := f.read(block):
            h.update(chunk)
    return h.hexdigest()


# -- one shot -------------------------------------------------------------------------------------------
@dataclass
class Frame:
    """One laser position's image in pixel values per second: value, variance, bad pixels."""

    value: np.ndarray  # (H, W, 3) float32, dark-subtracted, flat/vignetting corrected, per second
    variance: np.ndarray  # (H, W, 3) float32
    bad: np.ndarray  # (H, W) bool: saturated (dilated), under-exposed, not finite


def load_frame(shot: Shot, calib: Calibration, setup: ImportSetup, shape=None, region=None) -> Frame:
    """Read and correct the image(s) of one laser position (see the module's steps 1–2).

    ``region`` (v0, v1, u0, u1): correct only these rows and columns (the part under a window).
    """
    ldr = shot.files[0].suffix.lower() in LDR_SUFFIXES
    v0, v1, u0, u1 = region if region is not None else (0, None, 0, None)
    sl = (slice(v0, v1), slice(u0, u1))
    cut = lambda a: None if a is None else a[sl]  # noqa: E731
    if ldr:
        codes, tops = zip(*(read_ldr(p) for p in shot.files))
        _check_shapes(shot, [c.shape for c in codes], shape)
        times = shot.exposures if len(shot.exposures) == len(codes) else shot.exposures * len(codes)
        value, var, sat, under = merge_exposures(
            [c[sl] for c in codes], times, top=tops[0], gain=calib.gain, read_noise=calib.read_noise
        )
        exposure = 1.0  # the merge is per second already
        bad = sat | under
        if calib.dark is not None:  # a dark frame in codes at the first exposure
            value = value - calib.dark[sl] / np.float32(times[0])
    else:
        frames = [read_hdr(p) for p in shot.files]
        _check_shapes(shot, [f.shape for f in frames], shape)
        for p, f in zip(shot.files, frames):
            if not np.isfinite(f.sum()) and not np.isfinite(f).all():  # one fast pass, then find the pixel
                r, c, ch = (int(i) for i in np.argwhere(~np.isfinite(f))[0])
                raise TranslucencyError(f"{p}: pixel (row {r}, column {c}, channel {ch}) is {f[r, c, ch]}")
        frames = [f[sl] for f in frames]
        bad = np.zeros(frames[0].shape[:2], bool)
        if np.isfinite(calib.saturation):
            for f in frames:
                bad |= (f >= np.float32(calib.saturation)).any(axis=-1)
        if len(frames) == 1:
            value = frames[0]
            var = np.float32(calib.gain) * np.maximum(value, 0) + np.float32(calib.read_noise**2)
        else:  # repeated frames: the mean, and the variance of the mean from their spread
            stack = np.stack(frames)
            value = stack.mean(axis=0)
            var = stack.var(axis=0, ddof=1) / np.float32(len(frames))
        exposure = shot.exposures[0]
        if calib.dark is not None:
            value = value - calib.dark[sl]
        if setup.floor is not None:
            bad |= (value < np.float32(setup.floor)).any(axis=-1)
    if setup.dilate and bad.any():
        bad = binary_dilation(bad, iterations=int(setup.dilate))
    corr = np.full(value.shape[:2] + (1,), 1.0 / exposure, np.float32)
    if len(calib.vignetting):
        full = shape or (value.shape if region is None else None)
        v, u = np.mgrid[0 : value.shape[0], 0 : value.shape[1]]
        corr = corr / calib.falloff(u + u0, v + v0, full)[..., None]
    if calib.flat is not None:
        corr = corr / cut(calib.flat)
    return Frame(value * corr, var * corr * corr, bad)


def _check_shapes(shot: Shot, shapes, shape) -> None:
    want = shape or shapes[0]
    for p, s in zip(shot.files, shapes):
        if tuple(s) != tuple(want):
            raise TranslucencyError(
                f"{p}: image of {s[1]} x {s[0]} pixels among images of {want[1]} x {want[0]} pixels"
            )


def resample_window(
    frame: Frame, calib: Calibration, setup: ImportSetup, x_i, origin
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One window (n, n, 3) of R_d·scale·power (pixel values per unit area), its variance and mask."""
    n = setup.window_pixels()
    p = setup.pitch
    centre = np.asarray(origin, float) + 0.5 * n * p
    dense = p * np.sqrt(float(calib.homography.pixels_per_mm2(centre[None])[0]))  # image px per pitch
    # at least one sub-sample per image pixel: every pixel under the window counts (and the variance of
    # the mean is that of n_eff independent pixels)
    s = max(int(setup.supersample), int(np.ceil(dense)))
    sub = (np.arange(n * s) + 0.5) * (p / s)  # sub-sample positions inside the window, mm
    X, Y = np.meshgrid(origin[0] + sub, origin[1] + sub)
    xy = np.stack([X.ravel(), Y.ravel()], axis=1)
    uv = calib.homography.to_image(xy)
    Hh, Ww = frame.value.shape[:2]
    u, v = uv[:, 0], uv[:, 1]
    inside = (u >= 0) & (u <= Ww - 1) & (v >= 0) & (v <= Hh - 1)
    j0 = np.clip(np.floor(u), 0, Ww - 2).astype(np.int64)
    i0 = np.clip(np.floor(v), 0, Hh - 2).astype(np.int64)
    fu = np.clip(u - j0, 0, 1).astype(np.float32)[:, None]
    fv = np.clip(v - i0, 0, 1).astype(np.float32)[:, None]
    # value, variance and bad pixels in one table: four gathers by flat index, one bilinear blend
    table = np.concatenate([frame.value, frame.variance, frame.bad[..., None]], axis=2).reshape(-1, 7)
    k = i0 * Ww + j0
    a, b = table.take(k, axis=0), table.take(k + 1, axis=0)
    c, d = table.take(k + Ww, axis=0), table.take(k + Ww + 1, axis=0)
    mix = (a * (1 - fu) + b * fu) * (1 - fv) + (c * (1 - fu) + d * fu) * fv
    val, var = mix[:, :3], mix[:, 3:6]
    # a bad pixel spoils every read that gives it weight (at an exact pixel centre its neighbours have none)
    bad = (mix[:, 6] > 0) | ~inside
    ppm = calib.homography.pixels_per_mm2(xy).astype(np.float32)  # image pixels per mm² of sample
    if calib.pixel == "flux":  # power per pixel → power per mm²
        val = val * ppm[:, None]
        var = var * (ppm * ppm)[:, None]
    if setup.specular_radius > 0:
        bad |= np.hypot(xy[:, 0] - x_i[0], xy[:, 1] - x_i[1]) <= setup.specular_radius
    if setup.sample_size is not None:
        W, H = setup.sample_size
        bad |= (xy[:, 0] < 0) | (xy[:, 0] > W) | (xy[:, 1] < 0) | (xy[:, 1] > H)
    shape = (n, s, n, s)
    val = val.reshape(*shape, 3).mean(axis=(1, 3))
    n_eff = np.maximum(1.0, ppm.reshape(shape).mean(axis=(1, 3)) * p * p)
    var = var.reshape(*shape, 3).mean(axis=(1, 3)) / n_eff[..., None]
    mask = ~bad.reshape(shape).any(axis=(1, 3))
    return val, var, mask


def window_region(calib: Calibration, origin, side: float, shape) -> tuple[int, int, int, int]:
    """Rows v0..v1 and columns u0..u1 of the image under a window (+2 pixels for the bilinear reads)."""
    corners = np.array([[0, 0], [side, 0], [side, side], [0, side]]) + origin
    uv = calib.homography.to_image(corners)
    Hh, Ww = shape[:2]
    u0 = int(np.clip(np.floor(uv[:, 0].min()) - 2, 0, Ww - 2))
    v0 = int(np.clip(np.floor(uv[:, 1].min()) - 2, 0, Hh - 2))
    u1 = int(np.clip(np.ceil(uv[:, 0].max()) + 3, u0 + 2, Ww))
    v1 = int(np.clip(np.ceil(uv[:, 1].max()) + 3, v0 + 2, Hh))
    return v0, v1, u0, u1


def _shifted(calib: Calibration, region) -> Calibration:
    """The calibration's homography for a crop starting at row v0, column u0."""
    v0, _, u0, _ = region
    shift = np.array([[1, 0, -u0], [0, 1, -v0], [0, 0, 1.0]])
    return Calibration(type(calib.homography)(shift @ calib.homography.matrix), calib.scale, calib.pixel)


# -- the import ------------------------------------------------------------------------------------------
def _pfm_shape(path: Path) -> tuple[int, int] | None:
    """(H, W) from a PFM header, or None for other files."""
    if path.suffix.lower() != ".pfm":
        return None
    with open(path, "rb") as f:
        words = f.read(64).split()
    try:
        return int(words[2]), int(words[1])
    except (IndexError, ValueError):
        return None


def _image_shape(shot: Shot) -> tuple[int, int, int]:
    """(H, W, 3) of a shot's first image (every image of the import must have it)."""
    p = shot.files[0]
    return read_ldr(p)[0].shape if p.suffix.lower() in LDR_SUFFIXES else read_hdr(p).shape


def import_images(
    folder,
    positions,
    calibration: Calibration,
    out,
    setup: ImportSetup | None = None,
    *,
    overwrite: bool = False,
    inputs=(),
    progress: Callable[[int, int], None] | None = None,
    workers: int | None = None,
    views=(),
    scheduler: str | None = "threads",
) -> PlanarDataset:
    """Import a rig's photographs as a planar data set at ``out`` (resumable, chunk by chunk).

    Parameters
    ----------
    folder : path
        The images.
    positions : path or list of Shot
        The table of laser positions (:func:`read_positions`), or its rows.
    calibration : Calibration
        Homography, radiometric scale, corrections, noise model.
    out : path
        Zarr directory; an unfinished import of the same inputs resumes.
    setup : ImportSetup
        Output grid, window, masks, chunking.
    workers : int, optional
        Images read and resampled at once (threads; default min(4, CPUs)).
    scheduler : str, optional
        Where the chunks run: ``"threads"`` (this process, default), ``"local:N"`` or
        ``"tcp://HOST:PORT"`` (:mod:`translucency.cluster`): each chunk a task that reads its images and
        writes its part of the store and its done flag; the same bytes either way.  The images and the
        output must be visible to the workers at the same paths.
    views : sequence of (folder, positions, Calibration), optional
        The same laser positions photographed by further cameras (one row per position, in the same
        order; the laser positions are the first table's).  Each view is resampled onto the same windows
        with its own calibration and the views are averaged where all of them are valid: two cameras at
        opposite azimuths cancel the part of the exit radiance that leans away from the beam, which one
        oblique camera sees as a strong gradient across the window (see docs/rig.md, section 4).

    Returns
    -------
    PlanarDataset

    Examples
    --------
    >>> import tempfile
    >>> from translucency.rig.calibration import Homography
    >>> from translucency.rig.hdr import write_pfm
    >>> d = Path(tempfile.mkdtemp())
    >>> write_pfm(d / "a.pfm", np.full((64, 64, 3), 2.0, np.float32))
    >>> _ = (d / "pos.csv").write_text("file,x,y\\na.pfm,3.2,3.2\\n")
    >>> cal = Calibration(Homography.from_matrix([[10, 0, 0], [0, 10, 0], [0, 0, 1]]), scale=4.0)
    >>> out = Path(tempfile.mkdtemp()) / "out.zarr"
    >>> ds = import_images(d, d / "pos.csv", cal, out, ImportSetup(pitch=0.5, window=2.5))
    >>> ds.window, float(ds["R_d"][0, 2, 2, 0])
    ((5, 5), 0.5)
    """
    setup = setup or ImportSetup()
    setup.check()
    parse_scheduler(scheduler)  # a bad option is one line before any work
    folder = Path(folder)
    table = None
    if not isinstance(positions, list | tuple):
        table = Path(positions)
        positions = read_positions(table, folder)
    shots = list(positions)
    if not shots:
        raise TranslucencyError("positions: no laser positions")
    shape = _image_shape(shots[0])
    calibration.check(shape)
    for s in shots:  # PFM sizes from their headers, before any work (other formats: when read)
        for f in s.files:
            got = _pfm_shape(f)
            if got is not None and got != shape[:2]:
                raise TranslucencyError(
                    f"{f}: image of {got[1]} x {got[0]} pixels among images of {shape[1]} x {shape[0]} pixels"
                )
    H = calibration.homography
    others = []
    for v_folder, v_positions, v_calib in views:
        v_folder = Path(v_folder)
        v_table = None if isinstance(v_positions, list | tuple) else Path(v_positions)
        v_shots = list(v_positions) if v_table is None else read_positions(v_table, v_folder)
        if len(v_shots) != len(shots):
            raise TranslucencyError(
                f"views: {v_folder} has {len(v_shots)} laser positions, the first view {len(shots)}"
            )
        v_shape = _image_shape(v_shots[0])
        v_calib.check(v_shape)
        others.append((v_folder, v_table, v_shots, v_calib, v_shape))
    x_i = np.array(
        [s.position if s.units == "mm" else H.to_sample([s.position])[0] for s in shots], dtype=np.float64
    )
    n, p = setup.window_pixels(), setup.pitch
    centre = (np.floor(x_i / p) + 0.5) * p  # the window's centre pixel on the lattice of the acquisition
    origin = centre - p * n / 2.0
    files = [[str(f.relative_to(folder)) for f in s.files] for s in shots]
    workers = max(1, int(workers or min(4, os.cpu_count() or 1)))
    flat = [f for s in shots for f in s.files]
    with ThreadPoolExecutor(workers) as pool:  # reading, hashing and NumPy release the GIL: in parallel
        digest = dict(zip(flat, pool.map(sha256_file, flat)))
    hashes = [[digest[f] for f in s.files] for s in shots]
    view_provenance = []
    for v_folder, v_table, v_shots, v_calib, _ in others:
        v_flat = [f for sh in v_shots for f in sh.files]
        with ThreadPoolExecutor(workers) as pool:
            v_digest = dict(zip(v_flat, pool.map(sha256_file, v_flat)))
        view_provenance.append(
            {
                "folder": str(v_folder.resolve()),
                "positions": None
                if v_table is None
                else {"file": str(v_table), "sha256": sha256_file(v_table)},
                "files": [[str(f.relative_to(v_folder)) for f in sh.files] for sh in v_shots],
                "sha256": [[v_digest[f] for f in sh.files] for sh in v_shots],
                "power_W": [sh.power for sh in v_shots],
                "calibration": v_calib.describe(),
            }
        )
    provenance = {
        "folder": str(folder.resolve()),
        "positions": None if table is None else {"file": str(table), "sha256": sha256_file(table)},
        "files": files,
        "sha256": hashes,
        "power_W": [s.power for s in shots],
        "exposure_s": [list(s.exposures) for s in shots],
        "position_units": shots[0].units,
        "calibration": calibration.describe(),
    }
    if view_provenance:
        provenance["views"] = view_provenance
    request = json.loads(
        json.dumps(
            {
                "setup": asdict(setup),
                "sha256": hashes,
                "calibration": calibration.describe(),
                "views": [[v["sha256"], v["calibration"]] for v in view_provenance],
            }
        )
    )
    request["positions"] = x_i.round(9).tolist()
    header = {
        "format": FORMAT,
        "version": VERSION,
        "units": {"length": "mm", "R_d": "mm^-2", "variance": "mm^-4"},
        "pitch_mm": p,
        "window": [n, n],
        "n_points": len(shots),
        "chunk_points": setup.chunk_points,
        "dtype": setup.dtype,
        "sample": {
            "eta": setup.eta,
            "size_mm": None if setup.sample_size is None else list(setup.sample_size),
            "description": {"source": "rig photographs", "folder": str(folder)},
        },
        "acquisition": {
            "photons": None,
            "estimator": "HDR photographs, homography resampling",
            "noise_model": "repeated frames" if any(len(s.files) > 1 for s in shots) else "gain + read",
        },
        "provenance": provenance,
        "software": {"translucency": __version__},
        "request": request,
    }
    P, k = len(shots), setup.chunk_points
    job = _ImportJob(shots, calibration, shape, [o[2:] for o in others], setup, x_i, origin)
    with output_lock(out):
        view_inputs = [p for o in others for p in o[:2]]
        ds = create_dataset(out, header, overwrite=overwrite, inputs=[folder, table, *view_inputs, *inputs])
        g = ds.group
        g["x_i"][...] = x_i.astype(np.float32)
        g["window_origin"][...] = origin.astype(np.float32)
        done = np.asarray(g["chunk_done"][...])
        todo = [(c, c * k, min(P, (c + 1) * k)) for c in range(len(done)) if not done[c]]
        finished = P - sum(hi - lo for _, lo, hi in todo)  # points of the chunks done before
        if progress and finished:
            progress(finished, P)
        with open_cluster(scheduler) as cluster:
            if cluster is None:  # this process: chunk after chunk, a chunk's images in threads
                with ThreadPoolExecutor(workers) as pool:
                    for c, lo, hi in todo:
                        _import_chunk(job, ds, c, lo, hi, pool)
                        finished += hi - lo
                        if progress:
                            progress(finished, P)
            else:  # a task per chunk: each reads its images, writes its part of the store and its flag
                tasks = [(ds, c, lo, hi) for c, lo, hi in todo]
                for i, _ in cluster.run(_import_chunk, tasks, shared=(cluster.keep(job),)):
                    finished += todo[i][2] - todo[i][1]
                    if progress:
                        progress(finished, P)
        return ds


@dataclass
class _ImportJob:
    """What every chunk of an import needs besides its index range (sent to a cluster once)."""

    shots: list  # the first view's laser positions (Shot)
    calibration: Calibration
    shape: tuple  # its images' shape
    others: list  # further views: (shots, calibration, image shape)
    setup: ImportSetup
    x_i: np.ndarray  # (P, 2) laser positions, mm
    origin: np.ndarray  # (P, 2) window origins, mm

    def view(self, j: int, shot: Shot, calib: Calibration, shape) -> tuple:
        """One image → its window of R_d, variance and mask, normalised by scale and laser power."""
        side = self.setup.window_pixels() * self.setup.pitch
        region = window_region(calib, self.origin[j], side, shape)
        frame = load_frame(shot, calib, self.setup, shape, region)
        val, var, mask = resample_window(
            frame, _shifted(calib, region), self.setup, self.x_i[j], self.origin[j]
        )
        norm = (np.asarray(calib.scale, np.float64) * shot.power).astype(np.float32)
        return val / norm, var / (norm * norm), mask

    def point(self, j: int) -> tuple:
        """Laser position j → the mean of its views where all of them are valid."""
        val, var, mask = self.view(j, self.shots[j], self.calibration, self.shape)
        for v_shots, v_calib, v_shape in self.others:
            v_val, v_var, v_mask = self.view(j, v_shots[j], v_calib, v_shape)
            val, var, mask = val + v_val, var + v_var, mask & v_mask
        k = 1 + len(self.others)
        val, var = val / k, var / (k * k)
        if self.setup.beam_rms > 0:
            val = beam_correction(val, mask, self.x_i[j], self.origin[j], self.setup)
        return val, var, mask


def beam_correction(val, mask, x_i, origin, setup: ImportSetup) -> np.ndarray:
    r"""A window measured with a beam of finite width, brought to the pencil beam's response.

    A beam of irradiance profile B (normalised, isotropic) measures :math:`M = B * P`, for smooth P
    :math:`M \approx P + \tfrac{\langle\rho^2\rangle}{4} \nabla^2 P` (second order in the beam's
    size; a uniform disc of radius b has :math:`\langle\rho^2\rangle = b^2/2`).  The Laplacian is
    taken from a smooth radial fit of the window itself, two exponentials per channel on its ring
    means, where :math:`\nabla^2 (c e^{-ar}) = c (a^2 - a/r) e^{-ar}` — never from the noisy pixels —
    and :math:`P = M - \tfrac{\langle\rho^2\rangle}{4} \nabla^2 P` is applied at
    :math:`r \ge 2\sqrt{\langle\rho^2\rangle}` (closer, the expansion does not hold; those pixels
    are the beam's own, masked as specular in practice).

    Examples
    --------
    >>> setup = ImportSetup(pitch=0.1, window=4.1, beam_rms=0.2)
    >>> n = setup.window_pixels(); c = (np.arange(n) + 0.5) * 0.1 - 2.05
    >>> r = np.hypot(*np.meshgrid(c, c))
    >>> P = np.exp(-2 * r)[..., None].repeat(3, axis=2)
    >>> M = P * (1 + 0.04 / 4 * (4 - 2 / np.maximum(r, 1e-9)))[..., None]   # what the beam makes of P
    >>> out = beam_correction(M, np.ones((n, n), bool), (0.0, 0.0), (-2.05, -2.05), setup)
    >>> far = r > 0.5
    >>> bool(np.abs(out / P - 1)[far].max() < 0.25 * np.abs(M / P - 1)[far].max())
    True
    """
    m2 = float(setup.beam_rms) ** 2
    n, p = setup.window_pixels(), setup.pitch
    centres = (
        np.asarray(origin, float)[None, None]
        + (np.stack(np.meshgrid(np.arange(n), np.arange(n)), -1) + 0.5) * p
    )
    r = np.hypot(centres[..., 0] - x_i[0], centres[..., 1] - x_i[1])
    r_min = 2.0 * np.sqrt(m2)
    use = mask & (r >= max(r_min, setup.specular_radius, p))
    if use.sum() < 8:
        return val
    # ring means of half-pixel rings, weighted by their pixel counts
    ring = np.floor(r / (p / 2)).astype(int)
    keys, inv = np.unique(ring[use], return_inverse=True)
    count = np.bincount(inv).astype(float)
    r_g = np.bincount(inv, r[use]) / count
    Y = np.stack([np.bincount(inv, val[..., ch][use]) / count for ch in range(3)])
    W = np.broadcast_to(np.sqrt(count), Y.shape)
    c, a, _ = fit_exponentials_batched(r_g, W, Y, 2, n_starts=3)
    rr = np.maximum(r, 1e-9)[..., None, None]  # (n, n, 1, 1) against (3, 2)
    lap = np.sum(c * (a**2 - a / rr) * np.exp(-a * rr), axis=-1)  # (n, n, 3)
    out = np.array(val, dtype=np.float32, copy=True)
    far = r >= r_min
    out[far] = (val[far] - m2 / 4.0 * lap[far]).astype(np.float32)
    return out


def _import_chunk(job: _ImportJob, ds: PlanarDataset, c: int, lo: int, hi: int, pool=None) -> None:
    """Import chunk ``c`` (laser positions lo..hi), write it, then its done flag.

    A pure function of the images and its arguments: in this process (its images read in ``pool``'s
    threads) or as a task on a worker, it writes the same bytes.
    """
    setup, g = job.setup, ds.group
    n, p = setup.window_pixels(), setup.pitch
    R = np.zeros((hi - lo, n, n, 3), np.float32)
    V = np.zeros_like(R)
    M = np.zeros((hi - lo, n, n), bool)
    results = pool.map(job.point, range(lo, hi)) if pool is not None else map(job.point, range(lo, hi))
    for j, (val, var, mask) in zip(range(lo, hi), results):
        R[j - lo], V[j - lo], M[j - lo] = val, var, mask
    g["R_d"][lo:hi] = R.astype(setup.dtype)
    g["variance"][lo:hi] = V.astype(setup.dtype)
    g["mask"][lo:hi] = M
    g["specular"][lo:hi] = np.zeros((hi - lo, 3), np.float32)  # not measured by a camera
    total = np.where(M[..., None], R, 0).sum(axis=(1, 2)) * p * p
    g["total_diffuse"][lo:hi] = total.astype(np.float32)
    g["chunk_done"][c] = True  # last: the chunk is complete
