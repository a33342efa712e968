"""Camera calibration of a rig: the plane-to-image homography and the radiometric corrections.

The sample's top face is the plane z = 0 with sample coordinates (x, y) in mm; a camera maps it to image
pixels (u, v) (u to the right, v down; pixel [row, col] is centred at (u, v) = (col, row), the convention
of scikit-image and OpenCV) by a homography

.. math:: (u, v, 1)^T \\sim H\\, (x, y, 1)^T .

:class:`Homography` holds H; it comes from a 3×3 matrix (:meth:`Homography.from_matrix`), from four or more
marked points with known sample coordinates (:func:`homography_from_points`: the normalised direct linear
transform, Hartley & Zisserman alg. 4.2, refined by Levenberg–Marquardt on the image distances), or from a
photograph of a checkerboard lying on the sample plane (:func:`homography_from_checkerboard`).

The area Jacobian :math:`|\\det \\partial(u, v)/\\partial(x, y)|` (pixels per mm²) of H is what turns a
pixel's *flux* into a density on the sample (:meth:`Homography.pixels_per_mm2`).

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
from scipy.optimize import least_squares

from .._validate import TranslucencyError, as_float_array


@dataclass(frozen=True)
class Homography:
    """A plane-to-image homography: sample (x, y) in mm → image (u, v) in pixels.

    Examples
    --------
    >>> h = Homography.from_matrix([[10, 0, 5], [0, 10, 7], [0, 0, 1]])
    >>> h.to_image([[1.0, 2.0]]).tolist()
    [[15.0, 27.0]]
    >>> h.to_sample([[15.0, 27.0]]).tolist()
    [[1.0, 2.0]]
    >>> round(float(h.pixels_per_mm2([[0.0, 0.0]])[0]), 9)
    100.0
    """

    matrix: np.ndarray

    @classmethod
    def from_matrix(cls, matrix, name: str = "homography") -> Homography:
        """Check a 3×3 matrix (finite, well conditioned) and normalise it to H[2, 2] = 1 (or unit norm)."""
        H = as_float_array(name, matrix, shape=(3, 3))
        s = np.linalg.svd(H, compute_uv=False)
        if not s[-1] > 1e-12 * s[0]:
            raise TranslucencyError(f"{name}: the matrix is singular (singular values {s.tolist()})")
        H = H / (H[2, 2] if abs(H[2, 2]) > 1e-12 * s[0] else np.linalg.norm(H))
        return cls(H)

    @property
    def inverse(self) -> np.ndarray:
        return np.linalg.inv(self.matrix)

    def to_image(self, xy) -> np.ndarray:
        """(N, 2) sample points, mm → (N, 2) image points (u, v), pixels."""
        return _apply(self.matrix, xy)

    def to_sample(self, uv) -> np.ndarray:
        """(N, 2) image points (u, v), pixels → (N, 2) sample points, mm."""
        return _apply(self.inverse, uv)

    def pixels_per_mm2(self, xy) -> np.ndarray:
        """Area Jacobian |det ∂(u, v)/∂(x, y)| at sample points (N,), pixels² per mm².

        For :math:`w = h_3 \\cdot (x, y, 1)`: :math:`\\det J = \\det H / w^3` (H scaled so that the sign
        of w is positive on the visible side).
        """
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        w = self.matrix[2, 0] * xy[:, 0] + self.matrix[2, 1] * xy[:, 1] + self.matrix[2, 2]
        return np.abs(np.linalg.det(self.matrix) / w**3)

    def to_dict(self) -> dict:
        return {"matrix": self.matrix.tolist()}


def _apply(M: np.ndarray, pts) -> np.ndarray:
    p = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
    x, y = p[:, 0], p[:, 1]  # element-wise: a (N, 2) @ (2, 3) product is ten times slower in NumPy
    w = M[2, 0] * x + M[2, 1] * y + M[2, 2]
    out = np.empty_like(p)
    np.divide(M[0, 0] * x + M[0, 1] * y + M[0, 2], w, out=out[:, 0])
    np.divide(M[1, 0] * x + M[1, 1] * y + M[1, 2], w, out=out[:, 1])
    return out


def _normaliser(p: np.ndarray) -> np.ndarray:
    """Hartley's similarity: centroid to 0, mean distance √2."""
    c = p.mean(axis=0)
    d = np.sqrt(((p - c) ** 2).sum(axis=1)).mean()
    s = np.sqrt(2) / d if d > 0 else 1.0
    return np.array([[s, 0, -s * c[0]], [0, s, -s * c[1]], [0, 0, 1.0]])


def homography_from_points(sample_mm, image_px, *, refine: bool = True) -> tuple[Homography, float]:
    """Estimate H from N ≥ 4 marked points: sample coordinates (mm) and where they are in the image (px).

    The normalised DLT, then (``refine``) Levenberg–Marquardt on the reprojection error in the image.

    Returns
    -------
    Homography, float
        H and the RMS reprojection error, pixels.

    Examples
    --------
    >>> true = Homography.from_matrix([[20, 2, 40], [1, 18, 30], [0.001, 0.002, 1]])
    >>> xy = np.array([[0, 0], [10, 0], [10, 10], [0, 10], [5, 5]], float)
    >>> H, rms = homography_from_points(xy, true.to_image(xy))
    >>> bool(np.allclose(H.matrix, true.matrix, atol=1e-6)), rms < 1e-6
    (True, True)
    """
    xy = as_float_array("marked points (sample mm)", sample_mm, shape=(None, 2))
    uv = as_float_array("marked points (image px)", image_px, shape=(None, 2))
    if len(xy) != len(uv):
        raise TranslucencyError(f"marked points: {len(xy)} sample points but {len(uv)} image points")
    if len(xy) < 4:
        raise TranslucencyError(f"marked points: need at least 4 to fix a homography, got {len(xy)}")
    Tx, Tu = _normaliser(xy), _normaliser(uv)
    a, b = _apply(Tx, xy), _apply(Tu, uv)
    rows = []
    for (x, y), (u, v) in zip(a, b):
        rows.append([-x, -y, -1, 0, 0, 0, u * x, u * y, u])
        rows.append([0, 0, 0, -x, -y, -1, v * x, v * y, v])
    A = np.asarray(rows)
    _, s, vt = np.linalg.svd(A)
    if s[-2] < 1e-9 * s[0]:  # a second null direction: collinear or repeated points
        raise TranslucencyError(
            "marked points: degenerate (three or more on a line, or repeated); the homography is not fixed"
        )
    Hn = vt[-1].reshape(3, 3)
    M = np.linalg.inv(Tu) @ Hn @ Tx
    M = M / M[2, 2]
    if refine and len(xy) > 4:

        def resid(h):
            return (_apply(np.append(h, 1.0).reshape(3, 3), xy) - uv).ravel()

        M = np.append(least_squares(resid, M.ravel()[:8], method="lm").x, 1.0).reshape(3, 3)
    H = Homography.from_matrix(M, "homography from marked points")
    rms = float(np.sqrt(np.mean(np.sum((H.to_image(xy) - uv) ** 2, axis=1))))
    return H, rms


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


def homography_from_checkerboard(
    image: np.ndarray, inner: tuple[int, int], square_mm: float, origin_mm=(0.0, 0.0)
) -> tuple[Homography, float]:
    """H from a photograph of a checkerboard on the sample plane.

    ``inner`` = (columns, rows) of inner corners; corner (i, j) lies at ``origin_mm + square_mm·(i, j)``.
    Corners are found with Harris + sub-pixel refinement (scikit-image), kept where a small circle around
    them crosses light and dark four times (X-corners, not the board's outer L-corners); the four
    outermost give a first H, which orders all of them; the final H uses every corner.  A board looks
    alike turned by 90° or 180°: the labelling chosen is the one seen from above (the sample's z axis
    towards the camera) whose x axis runs most nearly left to right in the image.
    """
    from skimage.feature import corner_harris, corner_peaks, corner_subpix  # only for checkerboards

    nx, ny = (int(v) for v in inner)
    if nx < 2 or ny < 2:
        raise TranslucencyError(f"checkerboard: need at least 2 x 2 inner corners, got {inner}")
    grey = np.asarray(image, dtype=np.float64)
    grey = grey.mean(axis=2) if grey.ndim == 3 else grey
    grey = grey / (np.nanmax(grey) or 1.0)
    resp = corner_harris(grey, sigma=2)
    peaks = corner_peaks(resp, min_distance=5, threshold_rel=0.05)
    if len(peaks) < nx * ny:
        raise TranslucencyError(f"checkerboard: found {len(peaks)} corners, expected {nx * ny}")
    sub = corner_subpix(grey, peaks, window_size=9)
    sub = np.where(np.isfinite(sub), sub, peaks)
    keep = np.array([_is_saddle(grey, p) for p in sub])  # X-corners of four squares, not a board's L-corners
    sub, peaks = sub[keep], peaks[keep]
    if len(sub) < nx * ny:
        raise TranslucencyError(f"checkerboard: found {len(sub)} inner corners, expected {nx * ny}")
    strength = resp[peaks[:, 0], peaks[:, 1]]
    uv = sub[np.argsort(-strength)[: nx * ny], ::-1]
    ii, jj = np.meshgrid(np.arange(nx), np.arange(ny))
    grid = np.stack([ii.ravel(), jj.ravel()], axis=1).astype(float)
    # outer corners: extremes of u + v and u − v (clockwise in the image from the top left)
    s, d = uv.sum(1), uv[:, 0] - uv[:, 1]
    quad = uv[[np.argmin(s), np.argmax(d), np.argmax(s), np.argmin(d)]]
    corners = np.array([[0, 0], [nx - 1, 0], [nx - 1, ny - 1], [0, ny - 1]], float)
    xy = np.asarray(origin_mm, float) + square_mm * grid
    best = None
    # a board is symmetric: of its 8 labellings keep those seen from above (a camera on the +z side sees the
    # plane mirrored: det ∂(u,v)/∂(x,y) < 0) that fit every corner, and take the one whose x axis runs most
    # nearly left to right in the image
    for flip in (False, True):
        for k in range(4):
            order = np.roll(corners[::-1] if flip else corners, k, axis=0)
            try:
                first, _ = homography_from_points(order, quad, refine=False)
            except TranslucencyError:
                continue
            ordered = match_markers(grid, uv, first)
            if len(np.unique(ordered.round(6), axis=0)) < len(ordered):
                continue
            H, rms = homography_from_points(xy, ordered)
            c = xy.mean(axis=0)
            J = np.stack([H.to_image([c + [1e-3, 0]])[0], H.to_image([c + [0, 1e-3]])[0]], 1)
            J = J - H.to_image([c])[0][:, None]
            if np.linalg.det(J) < 0 and rms < 1.0 and (best is None or J[0, 0] > best[2]):
                best = (H, rms, J[0, 0])
    if best is None:
        raise TranslucencyError("checkerboard: the corners found do not form the board's grid")
    return best[0], best[1]


def _is_saddle(grey: np.ndarray, rc, radius: float = 3.5) -> bool:
    """Does a circle around (row, col) cross light and dark four times (an X-corner)?"""
    a = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    r = np.clip(np.round(rc[0] + radius * np.sin(a)).astype(int), 0, grey.shape[0] - 1)
    c = np.clip(np.round(rc[1] + radius * np.cos(a)).astype(int), 0, grey.shape[1] - 1)
    ring = grey[r, c]
    bright = ring > 0.5 * (ring.max() + ring.min())
    return int(np.count_nonzero(bright != np.roll(bright, 1))) == 4


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
    """
    from .hdr import read_hdr  # the readers of the frames

    path = Path(path)
    try:
        spec = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise TranslucencyError(f"{path}: not a readable JSON calibration ({type(exc).__name__})") from None
    if not isinstance(spec, dict):
        raise TranslucencyError(f"{path}: a calibration is a JSON object")
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
        H, rms = homography_from_points(p["sample_mm"], p["image_px"])
        source["rms_px"] = rms
    else:
        c = spec["checkerboard"]
        img = read_hdr(path.parent / c["image"])
        H, rms = homography_from_checkerboard(
            img, tuple(c["inner"]), float(c["square_mm"]), c.get("origin_mm", (0, 0))
        )
        source["rms_px"] = rms
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
