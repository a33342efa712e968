"""High-dynamic-range images of a rig: read OpenEXR, Radiance HDR and PFM; merge bracketed LDR exposures.

Every reader returns linear RGB as float32 of shape (H, W, 3), row 0 at the top of the picture.

* **PFM** (portable float map, ``PF`` colour / ``Pf`` grey) is read and written here with NumPy
  (little- or big-endian, rows stored bottom-up as the format says).
* **OpenEXR** and **Radiance HDR** (RGBE) are decoded by Mitsuba's ``Bitmap`` (already a dependency; no
  OpenEXR wheel needed), loaded only when such a file is read.
* **Bracketed LDR** exposures (8- or 16-bit PNG/TIFF/JPEG read by imageio) are merged by
  :func:`merge_exposures` — Debevec & Malik's weighted mean of ``f⁻¹(Z) / t`` with hat weights over the
  exposures whose value lies in the valid range, for a camera response ``f⁻¹`` given as a look-up table
  (linear by default).

Units: the pixel values of the camera (relative exitance), per second of exposure after a merge.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..._validate import TranslucencyError
from ...io.atomic import atomic_path

#: the suffixes read as HDR images, and the readers' names in messages
HDR_SUFFIXES = (".exr", ".hdr", ".pfm")
LDR_SUFFIXES = (".png", ".tif", ".tiff", ".jpg", ".jpeg")


def _rgb(arr: np.ndarray, path) -> np.ndarray:
    """(H, W, 3) float32 from grey, grey+alpha, RGB or RGBA."""
    arr = np.asarray(arr)
    if arr.ndim == 2:
        arr = arr[..., None]
    if arr.ndim != 3 or arr.shape[2] not in (1, 2, 3, 4):
        raise TranslucencyError(f"{path}: expected a grey or RGB image, got shape {arr.shape}")
    if arr.shape[2] in (1, 2):
        arr = np.repeat(arr[..., :1], 3, axis=2)
    return np.ascontiguousarray(arr[..., :3], dtype=np.float32)


def read_pfm(path) -> np.ndarray:
    """A PFM file as (H, W, 3) float32, top row first.

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "a.pfm"
    >>> write_pfm(p, np.arange(6, dtype=np.float32).reshape(1, 2, 3))
    >>> read_pfm(p)[0, 1].tolist()
    [3.0, 4.0, 5.0]
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise TranslucencyError(f"{path}: cannot read ({exc.strerror})") from None
    return _decode_pfm(data, path)


def _decode_pfm(data: bytes, path) -> np.ndarray:
    fields, pos = [], 0
    try:
        while len(fields) < 4:  # magic, width, height, scale: whitespace separated
            while data[pos : pos + 1].isspace():
                pos += 1
            end = pos
            while not data[end : end + 1].isspace():
                end += 1
            fields.append(data[pos:end].decode("ascii"))
            pos = end
        pos += 1  # exactly one whitespace byte before the raster
        magic, w, h, scale = fields[0], int(fields[1]), int(fields[2]), float(fields[3])
    except (IndexError, ValueError, UnicodeDecodeError):
        raise TranslucencyError(f"{path}: not a PFM file (bad header)") from None
    if magic not in ("PF", "Pf") or w < 1 or h < 1 or scale == 0:
        raise TranslucencyError(f"{path}: not a PFM file (header {fields})")
    c = 3 if magic == "PF" else 1
    dtype = np.dtype("<f4" if scale < 0 else ">f4")
    need = w * h * c * 4
    if len(data) - pos < need:
        raise TranslucencyError(f"{path}: truncated PFM ({len(data) - pos} of {need} raster bytes)")
    arr = np.frombuffer(data, dtype=dtype, count=w * h * c, offset=pos).reshape(h, w, c)[::-1]
    return _rgb(arr.astype(np.float32, copy=False), path)


def write_pfm(path, image: np.ndarray) -> None:
    """Write (H, W, 3) or (H, W) floats as a little-endian PFM (bottom row first, as the format says).

    Parameters
    ----------
    path : str or Path
        The file to write (not atomically: :func:`write_hdr` is).
    image : array (H, W, 3) or (H, W)
        Colour (``PF``) or grey (``Pf``) values, stored as float32.

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "g.pfm"
    >>> write_pfm(p, np.array([[1.0, 2.0], [3.0, 4.0]]))  # grey: rows stored bottom-up
    >>> data = p.read_bytes()
    >>> data[:12], np.frombuffer(data[12:], "<f4").tolist()
    (b'Pf\\n2 2\\n-1.0\\n', [3.0, 4.0, 1.0, 2.0])
    >>> read_pfm(p)[..., 0].tolist()  # read back top row first (grey as three equal channels)
    [[1.0, 2.0], [3.0, 4.0]]
    """
    image = np.asarray(image, dtype="<f4")
    colour = image.ndim == 3
    h, w = image.shape[:2]
    head = f"{'PF' if colour else 'Pf'}\n{w} {h}\n-1.0\n".encode("ascii")
    with open(path, "wb") as f:
        f.write(head)
        f.write(np.ascontiguousarray(image[::-1]).tobytes())


def _mitsuba_bitmap(path) -> np.ndarray:
    from ...mitsuba import mitsuba  # loaded only for EXR / HDR files (Dr.Jit's libLLVM must be set first)

    mi = mitsuba()
    try:
        bmp = mi.Bitmap(str(path))
    except Exception as exc:  # noqa: BLE001 — the decoder's fault is the file's, said in one line
        raise TranslucencyError(
            f"{path}: cannot decode ({type(exc).__name__}: {str(exc).splitlines()[0][:80]})"
        ) from None
    bmp = bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False)
    return _rgb(np.array(bmp, copy=False), path)


def write_exr(path, image: np.ndarray) -> None:
    """Write (H, W, 3) floats as an OpenEXR (or, by the suffix ``.hdr``, a Radiance RGBE) file via Mitsuba."""
    from ...mitsuba import mitsuba  # loaded only here (Dr.Jit's libLLVM must be set first)

    mi = mitsuba()
    mi.Bitmap(np.ascontiguousarray(image, dtype=np.float32)).write(str(path))


def write_hdr(path: Path, image: np.ndarray) -> None:
    """Write an image atomically (no reader sees half a file): PFM for a ``.pfm`` path, else by
    :func:`write_exr`."""
    with atomic_path(path) as tmp:
        (write_pfm if path.suffix == ".pfm" else write_exr)(tmp, image)


def read_hdr(path) -> np.ndarray:
    """An HDR image (``.exr``, ``.hdr``, ``.pfm``) as linear RGB float32 (H, W, 3).

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "a.pfm"
    >>> write_pfm(p, np.full((2, 3, 3), 0.5, np.float32))
    >>> read_hdr(p).shape
    (2, 3, 3)
    """
    path = Path(path)
    if not path.is_file():
        raise TranslucencyError(f"{path}: no such image")
    suffix = path.suffix.lower()
    if suffix == ".pfm":
        return read_pfm(path)
    if suffix in (".exr", ".hdr"):
        return _mitsuba_bitmap(path)
    raise TranslucencyError(f"{path}: not an HDR image (expected one of {', '.join(HDR_SUFFIXES)})")


def read_ldr(path) -> tuple[np.ndarray, int]:
    """An 8- or 16-bit image as (H, W, 3) integer codes and its largest code (255 or 65535)."""
    import imageio.v3 as iio  # imageio's plugin registry is only needed for LDR brackets

    path = Path(path)
    if not path.is_file():
        raise TranslucencyError(f"{path}: no such image")
    try:
        arr = iio.imread(path)
    except Exception as exc:  # noqa: BLE001 — the decoder's fault is the file's, said in one line
        raise TranslucencyError(f"{path}: cannot decode ({type(exc).__name__})") from None
    if arr.dtype not in (np.uint8, np.uint16):
        raise TranslucencyError(f"{path}: expected 8- or 16-bit codes, got {arr.dtype}")
    top = 255 if arr.dtype == np.uint8 else 65535
    if arr.ndim == 2:
        arr = arr[..., None]
    if arr.ndim != 3:
        raise TranslucencyError(f"{path}: expected a grey or RGB image, got shape {arr.shape}")
    arr = np.repeat(arr[..., :1], 3, axis=2) if arr.shape[2] < 3 else arr[..., :3]
    return arr, top


def hat_weights(z: np.ndarray, top: int, lo: int, hi: int) -> np.ndarray:
    """Debevec's hat weight of integer codes: 0 outside [lo, hi], rising to 1 in the middle."""
    z = np.asarray(z, dtype=np.float32)
    mid = 0.5 * (lo + hi)
    w = np.where(z <= mid, z - lo, hi - z) / max(mid - lo, 1.0)
    return np.clip(w, 0.0, 1.0) * ((z >= lo) & (z <= hi))


def merge_exposures(
    codes,
    times,
    *,
    top: int = 255,
    response=None,
    lo: int | None = None,
    hi: int | None = None,
    read_noise: float = 0.0,
    gain: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Merge bracketed exposures into radiance per second: Debevec & Malik's weighted mean.

    .. math:: E = \\frac{\\sum_j w(Z_j)\\, f^{-1}(Z_j) / t_j}{\\sum_j w(Z_j)}

    with the hat weight w over the valid codes [lo, hi] (default [1, top − 1]: every code but black and
    clipped; the weight falls to 0 at both ends, so a long exposure's faint codes count little unless no
    other exposure saw the pixel).

    Parameters
    ----------
    codes : sequence of (H, W, 3) integer arrays
        One image per exposure.
    times : sequence of float
        Exposure times, s.
    top : int
        Largest code (255 for 8 bits, 65535 for 16 bits).
    response : array_like, shape (top + 1,), optional
        Inverse camera response f⁻¹: linear exposure of each code (default: the code itself, linear).
    read_noise, gain : float
        Noise model of one exposure in codes: Var(Z) = gain · Z + read_noise² (linear response); gives
        the variance of E by the same weights.

    Returns
    -------
    E, variance, saturated, under : arrays (H, W, 3), (H, W, 3), (H, W) bool, (H, W) bool
        Merged radiance per second; its variance; pixels with a channel in no exposure's valid range,
        above it in some (saturated even at the shortest); pixels with a channel below ``lo`` in every
        exposure (under-exposed even at the longest: that channel keeps the longest exposure's value).

    Examples
    --------
    >>> E = np.array([[[10.0, 100.0, 1000.0]]])
    >>> shots = [np.clip(E * t, 0, 255).astype(np.uint16) for t in (1.0, 0.1)]
    >>> np.round(merge_exposures(shots, [1.0, 0.1])[0], 1).tolist()
    [[[10.0, 100.0, 1000.0]]]
    """
    times = np.asarray(times, dtype=np.float64)
    if len(codes) != len(times) or len(codes) < 1:
        raise TranslucencyError(f"exposures: {len(codes)} images for {len(times)} exposure times")
    if not np.all(np.isfinite(times) & (times > 0)):
        raise TranslucencyError(f"exposure times: must be positive seconds, got {times.tolist()}")
    lo = 1 if lo is None else int(lo)
    hi = top - 1 if hi is None else int(hi)
    if not 0 <= lo < hi <= top:
        raise TranslucencyError(f"valid codes: need 0 <= lo < hi <= {top}, got [{lo}, {hi}]")
    lut = np.arange(top + 1, dtype=np.float32) if response is None else np.asarray(response, np.float32)
    if lut.shape != (top + 1,) or not np.all(np.isfinite(lut)) or np.any(np.diff(lut) < 0):
        raise TranslucencyError(f"response: expected {top + 1} finite, non-decreasing values")
    shape = np.shape(codes[0])
    num = np.zeros(shape, np.float32)
    den = np.zeros(shape, np.float32)
    var = np.zeros(shape, np.float32)
    low = np.ones(shape, bool)  # below lo in every exposure (per channel)
    slope = np.gradient(lut)  # d f⁻¹ / dZ, for the variance
    longest = int(np.argmax(times))
    for z, t in zip(codes, times):
        if np.shape(z) != shape:
            raise TranslucencyError(f"exposures: image of shape {np.shape(z)} among images of shape {shape}")
        z = np.asarray(z)
        w = hat_weights(z, top, lo, hi)
        e = lut[z] / np.float32(t)
        num += w * e
        den += w
        var += w * w * (slope[z] ** 2) * (gain * z + read_noise**2) / np.float32(t * t)
        low &= z < lo
    ok = den > 0
    zl = np.asarray(codes[longest])
    tl = np.float32(times[longest])
    # a channel too dark in every exposure keeps the longest exposure's value (flagged under-exposed)
    E = np.where(ok, num / np.where(ok, den, 1), lut[zl] / tl).astype(np.float32)
    dark_var = (slope[zl] ** 2) * (gain * zl + read_noise**2 + 1 / 12) / (tl * tl)  # + quantisation
    V = np.where(ok, var / np.where(ok, den, 1) ** 2, dark_var).astype(np.float32)
    under = (~ok & low).any(axis=2)
    saturated = (~ok & ~low).any(axis=2)  # no usable exposure and not for want of light: too bright
    return E, V, saturated, under
