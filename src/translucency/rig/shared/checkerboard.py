"""The plane-to-image homography from a photograph of a checkerboard lying on the sample plane, by OpenCV.

The inner corners are found by ``cv2.findChessboardCornersSB`` (on the photograph scaled to 8 bits) and
refined by ``cv2.cornerSubPix`` (on the photograph in floating point); both use the rig's pixel
convention (integer coordinates are pixel centres, :mod:`.homography`), so the corners need no shift.
The corners' sample coordinates follow from the board's labelling, and H from
:func:`.homography.homography_from_points` over all of them.
"""

from __future__ import annotations

import numpy as np

from ..._extras import require
from ..._validate import TranslucencyError
from .homography import Homography, homography_from_points

#: the largest RMS distance (pixels) between the corners found and the board's grid seen through H
MAX_RMS_PX = 1.0


def homography_from_checkerboard(
    image: np.ndarray,
    inner: tuple[int, int],
    square_mm: float,
    origin_mm=(0.0, 0.0),
    *,
    name: str = "checkerboard",
) -> tuple[Homography, float]:
    """H from a photograph of a checkerboard on the sample plane, and its RMS reprojection error (px).

    ``inner`` = (columns, rows) of inner corners; corner (i, j) lies at ``origin_mm + square_mm·(i, j)``
    mm.  A board looks alike turned by 180° (and by 90° if square): of the labellings it cannot tell
    apart, the one chosen is seen from above (the sample's z axis towards the camera: a camera on the
    +z side sees the plane mirrored, det ∂(u, v)/∂(x, y) < 0) with its x axis most nearly left to right
    in the image — put the board's origin accordingly.  Errors are one line prefixed by ``name``.

    Parameters
    ----------
    image : array (H, W) or (H, W, 3)
        The photograph (any scale: it is normalised).
    inner : (int, int)
        Inner corners (columns, rows) of the board.
    square_mm : float
        The side of a square, mm.
    origin_mm : (float, float)
        Where inner corner (0, 0) lies on the sample, mm.
    name : str
        What messages call the photograph.

    Returns
    -------
    H : Homography
        Sample (mm) → image (px).
    rms : float
        RMS distance (px) of the corners found from the board's grid seen through H.

    Examples
    --------
    A board of 5 × 4 squares of 0.5 mm seen from above at 16 px a square (32 px/mm; y up the sample,
    so v runs down the image), a white margin of two squares around it:

    >>> v, u = np.mgrid[0:144, 0:144]
    >>> col, row = (u - 31.5) // 16, (111.5 - v) // 16
    >>> on = (col >= 0) & (col < 5) & (row >= 0) & (row < 4)
    >>> img = np.where(on & ((col + row) % 2 == 0), 0.05, 0.95)
    >>> H, rms = homography_from_checkerboard(img, (4, 3), 0.5)
    >>> H.to_image([[0.0, 0.0], [0.5, 0.0], [0.0, 0.5]]).round(2).tolist(), round(rms, 3)
    ([[47.5, 95.5], [63.5, 95.5], [47.5, 79.5]], 0.0)
    >>> round(float(H.pixels_per_mm2([[1.0, 0.75]])[0]), 1)  # 32²
    1024.0
    >>> try:
    ...     homography_from_checkerboard(img, (5, 3), 0.5)
    ... except TranslucencyError as exc:
    ...     print(exc)
    checkerboard: OpenCV finds no 5 x 3 grid of inner corners
    """
    nx, ny = (int(v) for v in inner)
    uv = find_corners(image, (nx, ny), name=name)
    k = np.arange(nx * ny)
    g = np.stack([k % nx, k // nx], axis=1).astype(np.float64)
    # the labelling: each symmetry A of the grid maps the centred indices g − c to A (g − c); the image's
    # Jacobian with respect to the new indices is J A⁻¹ = J Aᵀ
    c = 0.5 * np.array([nx - 1, ny - 1])
    J = homography_from_points(g, uv, name=name)[0].jacobian([c])[0]
    best = max(
        (A for A in _symmetries(nx == ny) if np.linalg.det(J @ A.T) < 0),
        key=lambda A: (J @ A.T)[0, 0] / np.linalg.norm((J @ A.T)[:, 0]),
    )
    xy = np.asarray(origin_mm, dtype=np.float64) + square_mm * ((g - c) @ best.T + c)
    H, rms = homography_from_points(xy, uv, name=name)
    if rms > MAX_RMS_PX:
        raise TranslucencyError(
            f"{name}: the corners found fit the board's grid to {rms:.2f} px rms only (> {MAX_RMS_PX:g})"
        )
    return H, rms


def find_corners(image: np.ndarray, inner: tuple[int, int], *, name: str = "checkerboard") -> np.ndarray:
    """The inner corners (nx·ny, 2) of a checkerboard photograph in pixels, in OpenCV's order (row by row
    of the pattern, nx to a row), found by ``cv2.findChessboardCornersSB`` on the photograph scaled to 8
    bits and refined by ``cv2.cornerSubPix`` on it in floating point."""
    cv2 = require("rig")  # the rig extra; OpenCV loads only where a calibration photograph is read

    nx, ny = (int(v) for v in inner)
    if nx < 2 or ny < 2:
        raise TranslucencyError(f"{name}: need at least 2 x 2 inner corners, got {inner}")
    grey = np.asarray(image, dtype=np.float64)
    grey = grey.mean(axis=2) if grey.ndim == 3 else grey
    grey = np.where(np.isfinite(grey), grey, 0.0)
    grey = np.clip(grey / (np.max(grey) or 1.0), 0.0, 1.0).astype(np.float32)
    flags = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE
    found, corners = cv2.findChessboardCornersSB(np.round(255 * grey).astype(np.uint8), (nx, ny), flags=flags)
    if not found:
        raise TranslucencyError(f"{name}: OpenCV finds no {nx} x {ny} grid of inner corners")
    uv = corners.reshape(-1, 2).astype(np.float64)
    spacing = np.linalg.norm(uv[:, None] - uv[None], axis=2)[~np.eye(len(uv), dtype=bool)].min()
    half = int(np.clip(round(0.25 * spacing), 2, 10))  # a window of ~half a square: one corner in it
    stop = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-4)
    return cv2.cornerSubPix(grey, corners, (half, half), (-1, -1), stop).reshape(-1, 2).astype(np.float64)


def _symmetries(square: bool) -> list[np.ndarray]:
    """The 2 × 2 maps of centred grid indices that map the grid onto itself (8 for a square board, else 4)."""
    flips = [np.diag([sx, sy]).astype(np.float64) for sx in (1, -1) for sy in (1, -1)]
    swap = np.array([[0.0, 1.0], [1.0, 0.0]])
    return flips + [A @ swap for A in flips] if square else flips
