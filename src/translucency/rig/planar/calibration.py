"""Camera calibration of a rig: the plane-to-image homography with the radiometric corrections.

The geometry and its conventions (sample mm, image pixels with integer coordinates at pixel centres,
H from sample to image) are :mod:`translucency.rig.shared.homography`'s; H comes from a 3×3 matrix
(:meth:`.Homography.from_matrix`), from four or more marked points with known sample coordinates
(:func:`.homography_from_points`, OpenCV's ``findHomography``) — found in a photograph of bright
markers by :func:`find_markers` and ordered by :func:`match_markers` — or from a photograph of a
checkerboard lying on the sample plane (:func:`.homography_from_checkerboard`, OpenCV's corners).

The area Jacobian :math:`|\\det \\partial(u, v)/\\partial(x, y)|` (pixels per mm²) of H is what turns a
pixel's *flux* into a density on the sample (:meth:`.Homography.pixels_per_mm2`).

:class:`Calibration` gathers H with the radiometric side: the scale (pixel value per unit exitance,
i.e. per W mm⁻² of light leaving the sample, per second of exposure), a dark frame, a flat field and a
vignetting polynomial, and the sensor's noise model.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..._validate import TranslucencyError
from ..shared.checkerboard import homography_from_checkerboard
from ..shared.homography import Homography, homography_from_points


def find_markers(image: np.ndarray, n: int, *, threshold: float | None = None) -> np.ndarray:
    """Centroids (u, v) in pixels of the ``n`` largest bright blobs of an image (intensity-weighted).

    Bright marker dots (retro-reflective stickers, LEDs) on a dark background; the threshold defaults to
    half the brightest value.
    """
    from skimage.measure import label, regionprops  # scikit-image only for calibration photographs

    grey = np.asarray(image, dtype=np.float64)
    grey = grey.mean(axis=2) if grey.ndim == 3 else grey
    thr = 0.5 * np.nanmax(grey) if threshold is None else threshold
    lab = label(grey > thr)
    regions = sorted(regionprops(lab, intensity_image=grey), key=lambda r: -r.area)
    if len(regions) < n:
        raise TranslucencyError(f"markers: found {len(regions)} bright blobs, expected {n}")
    cents = np.array([r.centroid_weighted for r in regions[:n]])  # (row, col)
    return cents[:, ::-1]


def match_markers(sample_mm, found_px, guess: Homography | None = None) -> np.ndarray:
    """Order found marker centroids like ``sample_mm``: nearest to each marker's predicted position.

    Without a ``guess``, the markers are matched by the order of their angle about the centroid (enough
    for markers on a convex ring; give a rough H otherwise).
    """
    xy = np.asarray(sample_mm, float)
    uv = np.asarray(found_px, float)
    if guess is not None:
        pred = guess.to_image(xy)
        d = np.linalg.norm(pred[:, None] - uv[None], axis=2)
        return uv[np.argmin(d, axis=1)]
    ang = lambda p: np.arctan2(p[:, 1] - p[:, 1].mean(), p[:, 0] - p[:, 0].mean())  # noqa: E731
    return uv[np.argsort(ang(uv))][np.argsort(np.argsort(ang(xy)))]


@dataclass
class Calibration:
    """Everything that turns a pixel value into R_d (mm⁻² per unit incident power) on the sample plane.

    Attributes
    ----------
    homography : Homography
        Sample (mm) → image (px).
    scale : float
        Pixel value per unit exitance (per W mm⁻² leaving the sample) and per second of exposure; from the
        user, or from a reference of known reflectance (:func:`scale_from_reference`).
    pixel : str
        ``"radiance"``: a pixel's value is a density (a camera's radiance; the usual case);
        ``"flux"``: a pixel's value is the power it collects, divided here by its footprint on the sample
        (the area Jacobian) before resampling.
    dark, flat : array (H, W, 3) or None
        Dark frame (subtracted, in the images' units) and flat field (divided; normalised to mean 1).
    vignetting : sequence of float
        Coefficients (k1, k2, ...) of the radial fall-off 1 + k1 ρ² + k2 ρ⁴ + …, ρ the distance from
        ``centre_px`` in units of the image half-diagonal; images are divided by it.
    gain, read_noise : float
        Noise model of a frame in pixel values: Var = gain · value + read_noise².
    saturation : float
        Pixel values at or above this (before any correction) are saturated.

    Examples
    --------
    The vignetting fall-off is 1 at the image centre and 1 + k1 + k2 a half-diagonal away (2.5 px in a
    4 × 3 image):

    >>> H = Homography.from_matrix(np.diag([10.0, 10.0, 1.0]))  # 10 px per mm
    >>> cal = Calibration(H, scale=4.0, vignetting=(-0.3, 0.05))
    >>> cal.falloff(np.array([1.5, 4.0]), np.array([1.0, 1.0]), (3, 4)).round(6).tolist()
    [1.0, 0.75]
    >>> cal.describe()["scale"], cal.describe()["saturation"]
    (4.0, None)
    >>> try:
    ...     Calibration(H, scale=(1.0, 2.0)).check((3, 4, 3))
    ... except TranslucencyError as exc:
    ...     print(exc)
    calibration scale: must be one positive number or three (R, G, B), got (1.0, 2.0)
    """

    homography: Homography
    scale: float | tuple = 1.0
    pixel: str = "radiance"
    dark: np.ndarray | None = None
    flat: np.ndarray | None = None
    vignetting: tuple = ()
    centre_px: tuple | None = None
    gain: float = 0.0
    read_noise: float = 0.0
    saturation: float = np.inf
    source: dict = field(default_factory=dict)

    def check(self, shape) -> None:
        """Refuse corrections that do not fit images of ``shape`` (H, W, 3)."""
        s = np.asarray(self.scale, dtype=np.float64)
        if s.shape == () and np.isnan(s):  # no scale in the file, no reference, no gain given
            raise TranslucencyError(
                "calibration scale: none given (pixel value per unit exitance per second): put a scale or a "
                "reference in the calibration file, or give gain=VALUE"
            )
        if s.shape not in ((), (3,)) or not np.all(np.isfinite(s) & (s > 0)):
            raise TranslucencyError(
                f"calibration scale: must be one positive number or three (R, G, B), got {self.scale}"
            )
        if self.pixel not in ("radiance", "flux"):
            raise TranslucencyError(f"calibration pixel: 'radiance' or 'flux', got {self.pixel!r}")
        for name, v in (("gain", self.gain), ("read_noise", self.read_noise)):
            if not (np.isfinite(v) and v >= 0):
                raise TranslucencyError(f"calibration {name}: must be a number >= 0, got {v}")
        for name, arr in (("dark frame", self.dark), ("flat field", self.flat)):
            if arr is None:
                continue
            if arr.shape != tuple(shape):
                raise TranslucencyError(f"{name}: shape {arr.shape} differs from the images' {tuple(shape)}")
            if not np.all(np.isfinite(arr)):
                raise TranslucencyError(f"{name}: holds NaN or infinite pixels")
        if self.flat is not None and not np.all(self.flat > 0):
            raise TranslucencyError("flat field: holds pixels <= 0")

    def falloff(self, u: np.ndarray, v: np.ndarray, shape) -> np.ndarray:
        """The vignetting factor at image points (u, v) (1 without coefficients)."""
        if not len(self.vignetting):
            return np.ones_like(u, dtype=np.float32)
        H, W = shape[:2]
        cu, cv = self.centre_px if self.centre_px is not None else ((W - 1) / 2, (H - 1) / 2)
        rho2 = ((u - cu) ** 2 + (v - cv) ** 2) / (0.25 * (W * W + H * H))
        f = np.ones_like(rho2)
        for k, c in enumerate(self.vignetting, start=1):
            f = f + c * rho2**k
        return f.astype(np.float32)

    def describe(self) -> dict:
        """JSON-friendly provenance (matrices, numbers, hashes of the frames)."""
        digest = lambda a: None if a is None else hashlib.sha256(a.tobytes()).hexdigest()  # noqa: E731
        return {
            "homography": self.homography.matrix.tolist(),
            "scale": np.asarray(self.scale, dtype=np.float64).tolist(),
            "pixel": self.pixel,
            "dark_sha256": digest(self.dark),
            "flat_sha256": digest(self.flat),
            "vignetting": list(self.vignetting),
            "centre_px": None if self.centre_px is None else list(self.centre_px),
            "gain": self.gain,
            "read_noise": self.read_noise,
            "saturation": None if not np.isfinite(self.saturation) else self.saturation,
            "source": self.source,
        }


def scale_from_reference(
    image: np.ndarray,
    homography: Homography,
    x_i,
    radius_mm: float,
    total,
    power: float = 1.0,
    inner_mm: float = 0.0,
):
    """The radiometric scale from a photograph of a reference of known total diffuse reflectance.

    The reference (a sample whose R_d integrates to ``total`` over the disc of ``radius_mm`` around the
    beam at ``x_i`` — or over the annulus ``inner_mm`` .. ``radius_mm``) is lit with ``power``; the image
    integrated over that region in sample-plane area, ∫ value dA = scale · total · power, gives the scale
    (pixel value per unit exitance), per channel for an RGB image and three totals.  A pixel's area on the
    sample is 1 / (pixels per mm²) of H.  An annulus matching the fit's (exclusion .. radius) carries the
    angular factor of the light the fit sees, not that of the light near the beam.

    Examples
    --------
    >>> H = Homography.from_matrix(np.diag([10.0, 10.0, 1.0]))
    >>> img = np.full((100, 100), 3.0)  # an exitance of 1 everywhere, seen at 3 per unit
    >>> round(scale_from_reference(img, H, (5.0, 5.0), 2.0, np.pi * 4.0), 1)  # a disc of pixels
    3.0
    """
    img = np.asarray(image, dtype=np.float64)
    img = img[..., None] if img.ndim == 2 else img
    Hh, Ww = img.shape[:2]
    v, u = np.mgrid[0:Hh, 0:Ww]
    xy = homography.to_sample(np.stack([u.ravel(), v.ravel()], 1))
    dist = np.hypot(xy[:, 0] - x_i[0], xy[:, 1] - x_i[1])
    inside = (dist <= radius_mm) & (dist >= inner_mm)
    area = 1.0 / homography.pixels_per_mm2(xy[inside])  # mm² per pixel
    integral = (img.reshape(-1, img.shape[2])[inside] * area[:, None]).sum(axis=0)
    total = np.asarray(total, dtype=np.float64)
    if not (np.all(total > 0) and power > 0 and np.all(integral > 0)):
        raise TranslucencyError("reference: need a positive total reflectance, power and image integral")
    scale = integral / (total * power)
    return float(scale[0]) if scale.size == 1 else scale


def _scale(value):
    arr = np.asarray(value, dtype=np.float64)
    return float(arr) if arr.ndim == 0 else tuple(float(v) for v in arr.ravel())


def load_calibration(path) -> Calibration:
    """A calibration from JSON.

    Keys: ``homography`` (3×3) **or** ``points`` ({"sample_mm": [[x, y], ...], "image_px": [[u, v], ...]})
    **or** ``checkerboard`` ({"image": file, "inner": [nx, ny], "square_mm": s, "origin_mm": [x, y]});
    ``scale``; optional ``pixel``, ``dark``, ``flat`` (image files, relative to the JSON), ``vignetting``,
    ``centre_px``, ``gain``, ``read_noise``, ``saturation``; or, instead of ``scale``, ``reference``
    ({"image": file, "x", "y": beam (mm), "radius_mm", "total": reflectance within that radius (one or
    R, G, B), "power": W, "exposure_s", optional "inner_mm": the total is over the annulus from there})
    — the scale from a photograph of a reference of known reflectance (:func:`scale_from_reference`),
    corrected like every shot.

    Parameters
    ----------
    path : str or Path
        The JSON file; the image files it names are relative to its folder.

    Returns
    -------
    Calibration
        With ``source``: the file, the method (``homography``, ``points``, ``checkerboard``) and the
        reprojection error ``rms_px`` of the last two.

    Raises
    ------
    TranslucencyError
        One line naming the file: unreadable, not one way to H, a bad value.

    Examples
    --------
    Four marked points 10 px per mm apart give H and its 100 px/mm²:

    >>> import json, tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> square = [[0, 0], [4, 0], [4, 4], [0, 4]]
    >>> marked = [[10 * x + 5, 10 * y + 7] for x, y in square]
    >>> spec = {"points": {"sample_mm": square, "image_px": marked}, "scale": 2.5}
    >>> _ = (d / "cal.json").write_text(json.dumps(spec))
    >>> cal = load_calibration(d / "cal.json")
    >>> cal.homography.to_image([[1.0, 2.0]]).round(6).tolist(), cal.scale, cal.source["method"]
    ([[15.0, 27.0]], 2.5, 'points')
    >>> round(float(cal.homography.pixels_per_mm2([[2.0, 2.0]])[0]), 6)
    100.0
    >>> _ = (d / "both.json").write_text(json.dumps({**spec, "homography": np.eye(3).tolist()}))
    >>> try:
    ...     load_calibration(d / "both.json")
    ... except TranslucencyError as exc:
    ...     print(str(exc).split("/")[-1])
    both.json: give exactly one of homography, points or checkerboard, got ['homography', 'points']
    """
    from ..shared.hdr import read_hdr  # the readers of the frames

    path = Path(path)
    spec = _read_spec(path)
    H, source = _homography(spec, path)
    frame = lambda key: None if spec.get(key) is None else read_hdr(path.parent / spec[key])  # noqa: E731
    flat = frame("flat")
    if flat is not None:
        flat = flat / np.float32(np.mean(flat))
    try:
        calib = Calibration(
            homography=H,
            scale=_scale(spec.get("scale", np.nan)),
            pixel=str(spec.get("pixel", "radiance")),
            dark=frame("dark"),
            flat=flat,
            vignetting=tuple(float(v) for v in spec.get("vignetting", ())),
            centre_px=None if spec.get("centre_px") is None else tuple(map(float, spec["centre_px"])),
            gain=float(spec.get("gain", 0.0)),
            read_noise=float(spec.get("read_noise", 0.0)),
            saturation=float(spec.get("saturation", np.inf)),
            source=source,
        )
        ref = spec.get("reference")
        if ref is not None:
            calib.scale = 1.0  # a placeholder while the frames are checked against the reference
            calib.scale = _reference_scale(calib, ref, read_hdr(path.parent / ref["image"]))
            source["scale"] = {"from reference": ref}
    except (TypeError, ValueError, KeyError) as exc:
        raise TranslucencyError(f"{path}: bad calibration value ({type(exc).__name__}: {exc})") from None
    return calib


def _read_spec(path: Path) -> dict:
    """The calibration file's JSON object, refused in one line otherwise."""
    try:
        spec = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise TranslucencyError(f"{path}: not a readable JSON calibration ({type(exc).__name__})") from None
    if not isinstance(spec, dict):
        raise TranslucencyError(f"{path}: a calibration is a JSON object")
    return spec


def _homography(spec: dict, path: Path):
    """H from the one way given (a matrix, marked points or a checkerboard) and the ``source`` record."""
    from ..shared.hdr import read_hdr  # the readers of the frames

    kinds = [k for k in ("homography", "points", "checkerboard") if k in spec]
    if len(kinds) != 1:
        raise TranslucencyError(
            f"{path}: give exactly one of homography, points or checkerboard, got {kinds}"
        )
    source = {"file": str(path), "method": kinds[0]}
    if kinds[0] == "homography":
        H = Homography.from_matrix(spec["homography"], f"{path}: homography")
    elif kinds[0] == "points":
        p = spec["points"]
        if not isinstance(p, dict) or "sample_mm" not in p or "image_px" not in p:
            raise TranslucencyError(f"{path}: points needs sample_mm and image_px lists")
        H, rms = homography_from_points(p["sample_mm"], p["image_px"], name=f"{path}: points")
        source["rms_px"] = rms
    else:
        c = spec["checkerboard"]
        img = read_hdr(path.parent / c["image"])
        H, rms = homography_from_checkerboard(
            img,
            tuple(c["inner"]),
            float(c["square_mm"]),
            c.get("origin_mm", (0, 0)),
            name=f"{path}: checkerboard {c['image']}",
        )
        source["rms_px"] = rms
    return H, source


def _reference_scale(calib: Calibration, ref: dict, image: np.ndarray):
    """The scale from a reference photograph, corrected like every shot (dark, vignetting, flat, time)."""
    calib.check(image.shape)
    img = image - (calib.dark if calib.dark is not None else 0)
    if len(calib.vignetting):
        v, u = np.mgrid[0 : img.shape[0], 0 : img.shape[1]]
        img = img / calib.falloff(u, v, img.shape)[..., None]
    if calib.flat is not None:
        img = img / calib.flat
    img = img / float(ref.get("exposure_s", 1.0))
    if calib.pixel == "flux":
        raise TranslucencyError("reference: only for radiance cameras (pixel = radiance)")
    return _scale(
        scale_from_reference(
            img,
            calib.homography,
            (float(ref["x"]), float(ref["y"])),
            float(ref["radius_mm"]),
            ref["total"],
            float(ref.get("power", 1.0)),
            float(ref.get("inner_mm", 0.0)),
        )
    )
