"""The plane-to-image homography of a rig's camera, and its estimate from marked points by OpenCV.

Conventions — stated here once for the whole of ``rig/`` and its calibration file:

* **sample plane**: the sample's top face z = 0, coordinates (x, y) in **mm**;
* **image**: (u, v) in **pixels**, u to the right (the column), v down (the row); pixel [row, col] is
  centred at (u, v) = (col, row) — integer coordinates are pixel centres, an image of W × H pixels spans
  −0.5 … W − 0.5 in u.  This is OpenCV's convention (and that of scikit-image's centroids), so points
  pass to and from OpenCV unchanged.  The one place a half-pixel shift appears is where a renderer's film
  coordinates (pixel col covering [col, col + 1)) become these: the virtual camera's intrinsics
  (:meth:`translucency.rig.planar.photographs.VirtualCamera.homography`, principal point W/2 − 0.5);
* **H** maps sample to image, :math:`(u, v, 1)^T \\sim H\\, (x, y, 1)^T`, normalised to H[2, 2] = 1.

:class:`Homography` holds H.  :func:`homography_from_points` estimates it from N ≥ 4 marked points with
``cv2.findHomography`` (least squares over every point, method 0, refined by OpenCV's Levenberg–Marquardt
on the image distances), after refusing point sets that cannot fix it (:func:`_check_marked`): fewer than
four, points that coincide, all (or all but one) of them on one line — for four points, any three on a
line — and, for any number, a configuration whose homography is ill-conditioned.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._extras import require
from ..._validate import TranslucencyError, as_float_array

#: two marked points closer than this fraction of the points' spread (RMS distance from their centroid)
#: coincide
DUPLICATE_TOL = 1e-3
#: points within this fraction of the spread of one line lie on it
COLLINEAR_TOL = 1e-2
#: the smallest accepted ratio σ₈/σ₁ of the singular values of the normalised direct-linear-transform
#: matrix: σ₈ = 0 leaves a second homography that fits, a small ratio one that fits almost as well
CONDITION_TOL = 1e-3


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
    >>> h.jacobian([[0.0, 0.0]]).tolist()
    [[[10.0, 0.0], [0.0, 10.0]]]
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

    def jacobian(self, xy) -> np.ndarray:
        """∂(u, v)/∂(x, y) at sample points (N, 2, 2), pixels per mm: (H₁₂ − (u, v)ᵀ h₃,₁₂) / w."""
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        M = self.matrix
        w = M[2, 0] * xy[:, 0] + M[2, 1] * xy[:, 1] + M[2, 2]
        uv = self.to_image(xy)
        return (M[None, :2, :2] - uv[:, :, None] * M[None, 2:3, :2]) / w[:, None, None]

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


def homography_from_points(sample_mm, image_px, *, name: str = "calibration") -> tuple[Homography, float]:
    """Estimate H from N ≥ 4 marked points: sample coordinates (mm) and where they are in the image (px).

    ``cv2.findHomography`` by least squares over every point (no outlier rejection: marked points are
    chosen, not matched), refined by Levenberg–Marquardt on the image distances.  Point sets that cannot
    fix H are refused first, in one line naming the points (counted from 1, in the order given) and
    prefixed by ``name``.  With exactly four points H fits them exactly: the error is 0 and checks
    nothing.

    Returns
    -------
    Homography, float
        H and the RMS reprojection error, pixels.

    Examples
    --------
    >>> true = Homography.from_matrix([[20, 2, 40], [1, 18, 30], [0.001, 0.002, 1]])
    >>> xy = np.array([[0, 0], [10, 0], [10, 10], [0, 10], [5, 5]], float)
    >>> H, rms = homography_from_points(xy, true.to_image(xy))
    >>> bool(np.allclose(H.matrix, true.matrix, atol=1e-6)), rms < 1e-4  # float32 points in OpenCV
    (True, True)
    >>> homography_from_points([[0, 0], [1, 1], [2, 2], [0, 5]], [[0, 0], [1, 1], [2, 2], [0, 5]])
    Traceback (most recent call last):
    ...
    translucency._validate.TranslucencyError: calibration: marked points 1, 2, 3 lie on one line in the \
sample plane; a homography needs four points with no three collinear
    """
    cv2 = require("rig")  # the rig extra; OpenCV loads only where a calibration is estimated

    xy = as_float_array(f"{name}: marked points (sample mm)", sample_mm, shape=(None, 2))
    uv = as_float_array(f"{name}: marked points (image px)", image_px, shape=(None, 2))
    _check_marked(xy, uv, name)
    # OpenCV takes points as float32 (CV_32FC2): Hartley-normalised first, they are rounded to ~1e-7 of
    # their spread rather than of their distance from the origin
    Tx, Tu = _normaliser(xy), _normaliser(uv)
    M, _ = cv2.findHomography(_apply(Tx, xy), _apply(Tu, uv), 0)
    if M is None:
        raise TranslucencyError(f"{name}: OpenCV found no homography through the marked points")
    H = Homography.from_matrix(np.linalg.inv(Tu) @ M @ Tx, f"{name}: homography from marked points")
    rms = float(np.sqrt(np.mean(np.sum((H.to_image(xy) - uv) ** 2, axis=1))))
    return H, rms


def _check_marked(xy: np.ndarray, uv: np.ndarray, name: str) -> None:
    """Refuse marked points that cannot fix a homography (see the module's notes), in one line."""
    if len(xy) != len(uv):
        raise TranslucencyError(
            f"{name}: {len(xy)} marked points in the sample plane but {len(uv)} in the image"
        )
    n = len(xy)
    if n < 4:
        raise TranslucencyError(f"{name}: a homography needs at least 4 marked points, got {n}")
    for pts, where in ((xy, "in the sample plane"), (uv, "in the image")):
        spread = np.sqrt(np.mean(np.sum((pts - pts.mean(axis=0)) ** 2, axis=1)))
        d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
        i, j = np.nonzero(np.triu(d <= DUPLICATE_TOL * spread, k=1))
        if len(i):
            raise TranslucencyError(f"{name}: marked points {i[0] + 1} and {j[0] + 1} coincide {where}")
        # without four points of which no three are collinear, all points but at most one lie on a line;
        # for four points, that is any three of them
        for off in (None, *range(n)):
            on = np.arange(n) if off is None else np.delete(np.arange(n), off)
            q = pts[on] - pts[on].mean(axis=0)
            normal = np.linalg.svd(q, full_matrices=False)[2][-1]  # of the best-fitting line
            if np.max(np.abs(q @ normal)) <= COLLINEAR_TOL * spread:
                which = f"all {n} marked points" if off is None else "marked points " + _listing(on + 1)
                raise TranslucencyError(
                    f"{name}: {which} lie on one line {where}; "
                    "a homography needs four points with no three collinear"
                )
    ratio = _dlt_condition(xy, uv)
    if ratio < CONDITION_TOL:
        raise TranslucencyError(
            f"{name}: the {n} marked points fix the homography poorly (σ₈/σ₁ = {ratio:.1e} < "
            f"{CONDITION_TOL:g}); spread them over the field of view, four or more with no three on a line"
        )


def _listing(numbers) -> str:
    return ", ".join(str(int(k)) for k in numbers)


def _dlt_condition(xy: np.ndarray, uv: np.ndarray) -> float:
    """σ₈/σ₁ of the direct-linear-transform matrix (2N × 9) of Hartley-normalised points.

    H's nine entries are its null vector; the eight other singular values must be positive for that
    vector to be unique.  For four points the matrix is 8 × 9 and σ₈ is its *last* singular value.
    """
    a, b = _apply(_normaliser(xy), xy), _apply(_normaliser(uv), uv)
    x, y, u, v = a[:, 0], a[:, 1], b[:, 0], b[:, 1]
    one, zero = np.ones_like(x), np.zeros_like(x)
    A = np.concatenate(
        [
            np.stack([x, y, one, zero, zero, zero, -u * x, -u * y, -u], axis=1),
            np.stack([zero, zero, zero, x, y, one, -v * x, -v * y, -v], axis=1),
        ]
    )
    s = np.linalg.svd(A, compute_uv=False)
    return float(s[7] / s[0])


def _normaliser(p: np.ndarray) -> np.ndarray:
    """Hartley's normalising similarity (3 × 3): centroid to 0, mean distance from it √2."""
    c = p.mean(axis=0)
    k = np.sqrt(2) / np.mean(np.sqrt(np.sum((p - c) ** 2, axis=1)))
    return np.array([[k, 0.0, -k * c[0]], [0.0, k, -k * c[1]], [0.0, 0.0, 1.0]])
