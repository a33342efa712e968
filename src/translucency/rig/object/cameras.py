r"""Calibrated cameras in OpenCV's conventions: projection, pixel rays, and their Mitsuba 3 sensor.

Conventions, stated once for every coordinate of an object rig (docs/reference/object-rig.md):

* **object frame**: the scanned mesh's coordinates, millimetres (after ``--scale``/``--up``);
* **camera frame**: OpenCV's — x to the right of the picture, y down, z forward (the optical axis);
  a point X of the object frame is :math:`x_c = R X + t` (R a rotation, t in mm), the camera centre
  :math:`C = -R^\top t`;
* **pixels**: :math:`(u, v) = (f_x x'' + c_x,\; f_y y'' + c_y)` with :math:`(x'', y'')` the
  distorted normalised coordinates of :math:`(x_c/z_c, y_c/z_c)` (OpenCV's five-coefficient model
  ``k1, k2, p1, p2, k3``); integer (u, v) is the *centre* of the pixel at column u, row v, and an
  image array is indexed ``[row, column]``.

A :class:`Camera` projects (``cv2.projectPoints``) and casts a ray through each pixel centre
(``cv2.undistortPoints`` refined by Newton steps on the lens model, :meth:`Camera.undistort`), with the
pixel's solid angle; :meth:`Camera.sensor_dict` gives the Mitsuba ``perspective`` sensor of a
distortion-free camera with square pixels and the principal point at the film's centre
(:math:`c_x = W/2 - 1/2`, since Mitsuba's pixel centres lie at half-integers), which is what the
virtual rig renders with.  Mitsuba's camera frame is (left, up, forward), so its ``to_world`` is
:math:`[R^\top \operatorname{diag}(-1, -1, 1) \mid C]`.

:func:`estimate_pose` finds R, t from marked points (``cv2.solvePnP``) and
:func:`calibrate_intrinsics` finds K and the distortion from checkerboard photographs
(``cv2.calibrateCamera``); both report their RMS reprojection error in pixels and refuse one above
its bound.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..._extras import require
from ..._validate import TranslucencyError

#: the largest RMS reprojection error (pixels) of a pose or an intrinsic calibration accepted by default
MAX_REPROJECTION_PX = 1.0


@dataclass(frozen=True)
class Camera:
    """A calibrated pinhole camera with lens distortion (OpenCV's model; module notes).

    Parameters
    ----------
    K : array_like, shape (3, 3)
        Intrinsic matrix [[f_x, 0, c_x], [0, f_y, c_y], [0, 0, 1]] in pixels.
    dist : array_like, shape (5,)
        Distortion ``k1, k2, p1, p2, k3`` (zeros: none).
    R : array_like, shape (3, 3)
        Rotation object → camera.
    t : array_like, shape (3,)
        Translation (mm): :math:`x_c = R X + t`.
    width, height : int
        Image size in pixels.
    name : str
        How messages name this camera.

    Examples
    --------
    >>> cam = Camera.looking_at((0.0, 0.0, 100.0), (0.0, 0.0, 0.0), 64, 48, fov_deg=30.0)
    >>> np.round(cam.project([[0.0, 0.0, 0.0]]), 6).tolist()
    [[31.5, 23.5]]
    """

    K: np.ndarray
    dist: np.ndarray
    R: np.ndarray
    t: np.ndarray
    width: int
    height: int
    name: str = "camera"
    reprojection_px: dict = field(default_factory=dict)  # what the calibration reported, for provenance

    def __post_init__(self):
        K = np.asarray(self.K, dtype=np.float64)
        dist = np.zeros(5) if self.dist is None else np.asarray(self.dist, dtype=np.float64).ravel()
        R = np.asarray(self.R, dtype=np.float64)
        t = np.asarray(self.t, dtype=np.float64).ravel()
        if K.shape != (3, 3) or not np.isfinite(K).all() or K[0, 0] <= 0 or K[1, 1] <= 0:
            raise TranslucencyError(f"{self.name}: K must be a finite 3 x 3 matrix with f_x, f_y > 0")
        if dist.size not in (4, 5, 8) or not np.isfinite(dist).all():
            raise TranslucencyError(f"{self.name}: dist must hold 4, 5 or 8 finite OpenCV coefficients")
        if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise TranslucencyError(f"{self.name}: R must be a 3 x 3 rotation matrix (orthonormal, det +1)")
        if t.shape != (3,) or not np.isfinite(t).all():
            raise TranslucencyError(f"{self.name}: t must be three finite numbers (mm)")
        if int(self.width) < 2 or int(self.height) < 2:
            raise TranslucencyError(f"{self.name}: width and height must be at least 2 pixels")
        for key, value in (("K", K), ("dist", dist), ("R", R), ("t", t)):
            object.__setattr__(self, key, value)
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))

    # -- construction ---------------------------------------------------------------------------------
    @classmethod
    def looking_at(cls, origin, target, width: int, height: int, *, fov_deg: float, up=None, name="camera"):
        """A distortion-free camera at ``origin`` looking at ``target`` (mm), horizontal field of view
        ``fov_deg``, square pixels, the principal point at the image centre (what Mitsuba renders).

        ``up`` (default +z, or +y when looking along z) points to the top of the picture."""
        o, c = np.asarray(origin, float), np.asarray(target, float)
        z = (c - o) / np.linalg.norm(c - o)
        hint = np.asarray(up, float) if up is not None else np.array([0.0, 0.0, 1.0])
        if abs(np.dot(hint / np.linalg.norm(hint), z)) > 0.99:
            hint = np.array([0.0, 1.0, 0.0])
        x = np.cross(z, hint)  # right of the picture
        x /= np.linalg.norm(x)
        y = np.cross(z, x)  # down the picture
        R = np.stack([x, y, z])
        f = 0.5 * width / np.tan(np.radians(fov_deg) / 2)
        K = np.array([[f, 0.0, 0.5 * width - 0.5], [0.0, f, 0.5 * height - 0.5], [0.0, 0.0, 1.0]])
        return cls(K, np.zeros(5), R, -R @ o, width, height, name)

    @classmethod
    def from_dict(cls, d: dict, name: str = "camera") -> Camera:
        """From ``{"K", "dist", "R" (or "rvec"), "t", "width", "height"}`` (JSON lists)."""
        try:
            if "R" not in d and "rvec" not in d:
                raise TranslucencyError(f"{name}: missing 'R' (or 'rvec')")
            R = d["R"] if "R" in d else _rotation(d["rvec"])
            return cls(d["K"], d.get("dist"), R, d["t"], int(d["width"]), int(d["height"]), name)
        except KeyError as exc:
            raise TranslucencyError(f"{name}: missing {exc.args[0]!r}") from None
        except TranslucencyError:
            raise  # the constructor's own one-line message (a ValueError too)
        except (TypeError, ValueError) as exc:
            raise TranslucencyError(f"{name}: not a camera ({exc})") from None

    def to_dict(self) -> dict:
        return {
            "K": self.K.tolist(),
            "dist": self.dist.tolist(),
            "R": self.R.tolist(),
            "t": self.t.tolist(),
            "width": self.width,
            "height": self.height,
        }

    def with_pose(self, R, t) -> Camera:
        return Camera(self.K, self.dist, R, t, self.width, self.height, self.name, self.reprojection_px)

    # -- geometry -------------------------------------------------------------------------------------
    @property
    def centre(self) -> np.ndarray:
        """The camera centre C = −Rᵀ t in the object frame, mm."""
        return -self.R.T @ self.t

    def project(self, points) -> np.ndarray:
        """Pixel coordinates (N, 2) of object points (N, 3) mm (``cv2.projectPoints``)."""
        cv2 = require("rig")  # the rig extra; OpenCV loads only where a camera projects

        X = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        rvec, _ = cv2.Rodrigues(self.R)
        uv, _ = cv2.projectPoints(X, rvec, self.t, self.K, self.dist)
        return uv.reshape(-1, 2)

    def depth(self, points) -> np.ndarray:
        """z_c (mm) of object points: positive in front of the camera."""
        return (np.asarray(points, dtype=np.float64).reshape(-1, 3) @ self.R.T + self.t)[:, 2]

    def pixel_rays(self, sub: int = 1, pixels=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r"""The ray through every pixel centre, row by row — or, with ``sub`` > 1, through the centres of
        each pixel's ``sub`` × ``sub`` sub-pixels (pixel k's at rows k·sub² … (k+1)·sub² − 1): origins
        (N, 3), unit directions (N, 3) in the object frame, and each ray's solid angle (sr).  With
        ``pixels`` (indices row by row), only theirs, in that order.

        A pixel's undistorted normalised coordinates (x, y) are those the lens model maps onto its centre
        (:meth:`undistort`).  The solid angle of a pixel is
        :math:`\cos^3\alpha / \det \partial(u, v)/\partial(x, y)` at the angle α of its direction off
        the axis (the determinant is :math:`f_x f_y` without distortion); a sub-pixel's is that at its
        own centre over sub².

        Examples
        --------
        >>> cam = Camera.looking_at((0.0, 0.0, 100.0), (0.0, 0.0, 0.0), 64, 48, fov_deg=30.0)
        >>> _, d1, omega1 = cam.pixel_rays()
        >>> _, d4, omega4 = cam.pixel_rays(sub=4)
        >>> d4.shape, round(float(omega4.sum() / omega1.sum()), 4)  # the same field, 16 rays a pixel
        ((49152, 3), 1.0)
        """
        sub = int(sub)
        v, u = np.mgrid[0 : self.height, 0 : self.width].astype(np.float64)
        uv = np.stack([u.ravel(), v.ravel()], axis=1)
        if pixels is not None:
            uv = uv[np.asarray(pixels, dtype=np.int64)]
        if sub > 1:  # the sub-pixel centres, pixel by pixel
            j, i = np.mgrid[0:sub, 0:sub].astype(np.float64)
            offset = (np.stack([i.ravel(), j.ravel()], axis=1) + 0.5) / sub - 0.5
            uv = (uv[:, None, :] + offset[None]).reshape(-1, 2)
        xy, J = self.undistort(uv)
        d_cam = np.column_stack([xy, np.ones(len(xy))])
        norm = np.linalg.norm(d_cam, axis=1)
        cos_a = 1.0 / norm
        omega = cos_a**3 / (J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]) / sub**2
        d = (d_cam / norm[:, None]) @ self.R  # Rᵀ d for each row
        return np.broadcast_to(self.centre, d.shape).copy(), d, omega

    def undistort(self, pixels) -> tuple[np.ndarray, np.ndarray]:
        """Undistorted normalised coordinates (x, y) = (x_c/z_c, y_c/z_c), shape (N, 2), of ``pixels``
        (N, 2), and the Jacobians ∂(u, v)/∂(x, y) of the lens model there, shape (N, 2, 2).

        ``cv2.undistortPoints`` gives the first guess (its fixed-point iteration stops after a few steps:
        0.01 px off at an 80° field with k1 = −0.1), Newton steps on OpenCV's model (:func:`_lens`) the
        rest, to 1e-6 px.  A pixel the model cannot reach, or reaches only where it folds over, is
        refused in one line.

        Examples
        --------
        >>> cam = Camera.looking_at((0.0, 0.0, 100.0), (0.0, 0.0, 0.0), 64, 48, fov_deg=30.0)
        >>> cam = Camera(cam.K, [-0.1, 0.0, 0.0, 0.0, 0.0], cam.R, cam.t, 64, 48)
        >>> xy, J = cam.undistort([[31.5, 23.5], [63.5, 23.5]])
        >>> np.round(xy, 6).tolist()  # the edge: x (1 − 0.1 x²) = tan 15°
        [[0.0, 0.0], [0.269916, 0.0]]
        """
        cv2 = require("rig")  # the rig extra; OpenCV loads only where a camera casts rays

        uv = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        if not np.isfinite(uv).all():
            raise TranslucencyError(f"{self.name}: pixels to undistort must be finite")
        f, c = np.array([self.K[0, 0], self.K[1, 1]]), self.K[:2, 2]
        xy = cv2.undistortPoints(uv.reshape(-1, 1, 2), self.K, self.dist).reshape(-1, 2)
        # Newton: xy ← xy − J⁻¹ r with r the miss (px) of the pixel xy maps to, J = ∂(u, v)/∂(x, y)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            for _ in range(_NEWTON_STEPS + 1):
                xy_d, J = _lens(xy, self.dist)
                r = xy_d * f + c - uv
                J = J * f[None, :, None]
                det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
                miss = np.hypot(r[:, 0], r[:, 1])
                if (miss <= _ROUND_TRIP_PX).all():
                    break
                step = np.column_stack(
                    [J[:, 1, 1] * r[:, 0] - J[:, 0, 1] * r[:, 1], J[:, 0, 0] * r[:, 1] - J[:, 1, 0] * r[:, 0]]
                )
                xy = xy - step / det[:, None]
        bad = ~((miss <= _ROUND_TRIP_PX) & (det > 0))
        if bad.any():
            k = int(np.argmax(bad))
            raise TranslucencyError(
                f"{self.name}: the lens distortion cannot be inverted at pixel (u, v) = "
                f"({uv[k, 0]:g}, {uv[k, 1]:g}) (the model folds over there): check dist"
            )
        return xy, J

    # -- Mitsuba --------------------------------------------------------------------------------------
    def sensor_dict(self, spp: int) -> dict:
        """Mitsuba's ``perspective`` sensor of this camera (``hdrfilm``, box filter, ``spp`` samples).

        Only a distortion-free camera with square pixels and a centred principal point can be rendered so
        (the virtual rig's); another is refused in one line."""
        from ...mitsuba import perspective_to_world_dict  # heavy: Mitsuba loads only where a camera renders

        W, H = self.width, self.height
        fx, fy, cx, cy = self.K[0, 0], self.K[1, 1], self.K[0, 2], self.K[1, 2]
        if np.any(self.dist != 0) or abs(fx - fy) > 1e-9 * fx or abs(cx - (W / 2 - 0.5)) > 1e-6:
            raise TranslucencyError(
                f"{self.name}: Mitsuba renders only a distortion-free camera with square pixels and the "
                "principal point at the image centre"
            )
        if abs(cy - (H / 2 - 0.5)) > 1e-6:
            raise TranslucencyError(f"{self.name}: the principal point must be at the image centre to render")
        to_world = np.eye(4)
        to_world[:3, :3] = self.R.T @ np.diag([-1.0, -1.0, 1.0])
        to_world[:3, 3] = self.centre
        fov = float(np.degrees(2 * np.arctan(0.5 * W / fx)))
        return perspective_to_world_dict(to_world, fov, W, H, spp)


#: the largest distance (pixels) from a pixel's centre at which its undistorted ray may land
_ROUND_TRIP_PX = 1e-6
#: Newton steps of :meth:`Camera.undistort` at most (it converges quadratically: a few suffice)
_NEWTON_STEPS = 20


def _lens(xy: np.ndarray, dist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's lens model: distorted normalised coordinates (N, 2) of undistorted ones (N, 2) and its
    Jacobians ∂(x'', y'')/∂(x, y) (N, 2, 2), for 4, 5 or 8 coefficients k1, k2, p1, p2[, k3[, k4, k5, k6]].

    x'' = x ρ + 2 p1 x y + p2 (r² + 2x²), y'' = y ρ + p1 (r² + 2y²) + 2 p2 x y with the radial factor
    ρ = (1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ + k6 r⁶) (what ``cv2.projectPoints`` computes).
    """
    k1, k2, p1, p2, k3, k4, k5, k6 = np.concatenate([dist, np.zeros(8 - len(dist))])
    x, y = xy[:, 0], xy[:, 1]
    r2 = x * x + y * y
    num, den = 1 + r2 * (k1 + r2 * (k2 + r2 * k3)), 1 + r2 * (k4 + r2 * (k5 + r2 * k6))
    rho = num / den
    # dρ/d(r²) by the quotient rule
    drho = ((k1 + r2 * (2 * k2 + 3 * k3 * r2)) * den - num * (k4 + r2 * (2 * k5 + 3 * k6 * r2))) / den**2
    xd = x * rho + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * rho + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    cross = 2 * x * y * drho + 2 * p1 * x + 2 * p2 * y  # ∂x''/∂y = ∂y''/∂x
    J = np.empty((len(x), 2, 2))
    J[:, 0, 0] = rho + 2 * x * x * drho + 2 * p1 * y + 6 * p2 * x
    J[:, 0, 1] = cross
    J[:, 1, 0] = cross
    J[:, 1, 1] = rho + 2 * y * y * drho + 6 * p1 * y + 2 * p2 * x
    return np.column_stack([xd, yd]), J


def _rotation(rvec) -> np.ndarray:
    cv2 = require("rig")  # the rig extra; OpenCV loads only where a Rodrigues vector is read

    r = np.asarray(rvec, dtype=np.float64).reshape(3, 1)
    return cv2.Rodrigues(r)[0]


def reprojection_rms(camera: Camera, points, pixels) -> float:
    """RMS distance (pixels) between marked ``pixels`` (N, 2) and the projections of ``points`` (N, 3)."""
    d = camera.project(points) - np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    return float(np.sqrt(np.mean(np.sum(d * d, axis=1))))


def estimate_pose(
    camera: Camera, points, pixels, *, max_rms_px: float = MAX_REPROJECTION_PX
) -> tuple[Camera, float]:
    """The pose (R, t) of ``camera`` (its K and distortion) from object points seen at marked pixels.

    ``cv2.solvePnP`` (SQPnP, then Levenberg–Marquardt refinement) on N ≥ 6 points (mm) marked at
    ``pixels`` (N, 2); returns the camera with that pose and the RMS reprojection error (px).  A pose
    whose error exceeds ``max_rms_px``, or that puts a marked point behind the camera, is refused in one
    line naming the camera.
    """
    cv2 = require("rig")  # the rig extra; OpenCV loads only where a pose is estimated

    X = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    uv = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    if len(X) != len(uv):
        raise TranslucencyError(f"{camera.name}: {len(X)} marked points but {len(uv)} pixel positions")
    if len(X) < 6:
        raise TranslucencyError(f"{camera.name}: a pose needs at least 6 marked points, got {len(X)}")
    if not (np.isfinite(X).all() and np.isfinite(uv).all()):
        raise TranslucencyError(f"{camera.name}: marked points must be finite")
    ok, rvec, tvec = cv2.solvePnP(X, uv, camera.K, camera.dist, flags=cv2.SOLVEPNP_SQPNP)
    if not ok:
        raise TranslucencyError(f"{camera.name}: OpenCV finds no pose for the marked points")
    rvec, tvec = cv2.solvePnPRefineLM(X, uv, camera.K, camera.dist, rvec, tvec)
    posed = camera.with_pose(cv2.Rodrigues(rvec)[0], tvec.ravel())
    rms = reprojection_rms(posed, X, uv)
    if rms > max_rms_px:
        raise TranslucencyError(
            f"{camera.name}: the pose fits the marked points to {rms:.2f} px rms (> {max_rms_px:g} px): "
            "check the marks or the intrinsics"
        )
    if (posed.depth(X) <= 0).any():
        raise TranslucencyError(f"{camera.name}: the pose puts marked points behind the camera")
    return posed, rms


def calibrate_intrinsics(
    images,
    inner: tuple[int, int],
    square_mm: float,
    *,
    name: str = "camera",
    max_rms_px: float = MAX_REPROJECTION_PX,
    fix_aspect: bool = False,
    zero_tangent: bool = False,
) -> tuple[np.ndarray, np.ndarray, float]:
    """K and the distortion of a camera from photographs of a flat checkerboard in several poses.

    Corners by ``cv2.findChessboardCornersSB`` and ``cv2.cornerSubPix``
    (:mod:`translucency.rig.shared.checkerboard`), then ``cv2.calibrateCamera`` with k3 fixed at zero
    (five coefficients, the last 0).  Returns (K, dist, RMS reprojection error in px); refuses fewer than
    three photographs, photographs of different sizes, one without the board, or an error above
    ``max_rms_px``.

    ``fix_aspect`` holds f_x/f_y at 1 (square pixels); ``zero_tangent`` holds p1 = p2 = 0 (a lens without
    decentring), which pins the principal point: free, p1 and p2 trade off against it (on eight 240 × 180
    px photographs of a 7 × 5 board, c is found within ≈ 1.5 px with them free, 0.6 px without).
    """
    cv2 = require("rig")  # the rig extra; OpenCV loads only where a camera is calibrated
    from ..shared.checkerboard import find_corners  # used here only, with OpenCV (above)

    nx, ny = (int(v) for v in inner)
    k = np.arange(nx * ny)
    board = np.column_stack([(k % nx) * square_mm, (k // nx) * square_mm, np.zeros(nx * ny)]).astype(
        np.float32
    )
    images = list(images)
    if len(images) < 3:
        raise TranslucencyError(
            f"{name}: intrinsics need at least 3 checkerboard photographs, got {len(images)}"
        )
    obj, img, shape = [], [], None
    for i, image in enumerate(images):
        arr = np.asarray(image)
        if shape is not None and arr.shape[:2] != shape:
            raise TranslucencyError(
                f"{name}: checkerboard photograph {i} is {arr.shape[:2]}, the first {shape}"
            )
        shape = arr.shape[:2]
        uv = find_corners(arr, (nx, ny), name=f"{name}: checkerboard photograph {i}")
        obj.append(board)
        img.append(uv.astype(np.float32).reshape(-1, 1, 2))
    flags = cv2.CALIB_FIX_K3 | (cv2.CALIB_FIX_ASPECT_RATIO if fix_aspect else 0)
    flags |= cv2.CALIB_ZERO_TANGENT_DIST if zero_tangent else 0
    H, W = shape
    rms, K, dist, _, _ = cv2.calibrateCamera(obj, img, (W, H), None, None, flags=flags)
    if not np.isfinite(rms) or rms > max_rms_px:
        raise TranslucencyError(
            f"{name}: the checkerboards fit the camera model to {rms:.2f} px rms (> {max_rms_px:g} px)"
        )
    return K, dist.ravel()[:5], float(rms)


__all__ = [
    "Camera",
    "MAX_REPROJECTION_PX",
    "calibrate_intrinsics",
    "estimate_pose",
    "reprojection_rms",
]
