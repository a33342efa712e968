"""Virtual calibration targets: checkerboard poses in front of a camera and their Mitsuba photographs.

What a lab photographs to calibrate a camera's intrinsics (:func:`.cameras.calibrate_intrinsics`), made
by the virtual object rig so that the calibration can be rehearsed on photographs no one wrote by hand.

Conventions (those of :mod:`.cameras`): lengths in mm; a board pose is the 4 × 4 matrix taking the
board's own frame to the object frame; in the board's frame the inner corner (i, j) lies at
(square_mm·i, square_mm·j, 0) and the squares reach one square beyond the corner grid on every side
(:func:`translucency.mitsuba.checkerboard_scene`); the board glows on its +z side, which faces the
camera.  A photograph is an (H, W, 3) float32 array of radiance (white squares 1, black 0), indexed
``[row, column]`` with integer (u, v) = (column, row) the pixel's centre.

:func:`checkerboard_poses` draws the poses: the board's centre on a ray near the optical axis, tilted by
15°–35° about an axis in the picture's plane whose direction turns from pose to pose (tilts in varied
directions fix the focal length and the principal point), turned by up to ±20° in the picture's plane,
at about the distance where it covers a fraction of the picture drawn in 30–60 %; a pose is kept when its
outline (the quadrilateral through the projections of its four outer corners) covers 30–60 % of the
picture and lies a margin (3 % of the picture's smaller side, ≥ 2 px) inside the image, else drawn again.
"""

from __future__ import annotations

import numpy as np

from ..._validate import TranslucencyError
from ...mitsuba import checkerboard_scene, mitsuba
from .cameras import Camera

#: the tilt (degrees) of a board out of the picture's plane: at least, at most
TILT_DEG = (15.0, 35.0)
#: the largest turn (degrees) of a board in the picture's plane
ROLL_DEG = 20.0
#: the fraction of the picture the board's outline covers: at least, at most
FILL = (0.3, 0.6)
#: draws of a pose before a board that cannot be placed is refused
_DRAWS = 500


def _check_board(camera: Camera, inner, square_mm: float, n: int) -> tuple[int, int]:
    try:
        nx, ny = (int(v) for v in inner)
    except (TypeError, ValueError):
        raise TranslucencyError(
            f"{camera.name}: inner must be two integers (columns, rows), got {inner!r}"
        ) from None
    if nx < 2 or ny < 2:
        raise TranslucencyError(
            f"{camera.name}: a checkerboard needs at least 2 x 2 inner corners, got {inner}"
        )
    if not (np.isfinite(square_mm) and square_mm > 0):
        raise TranslucencyError(f"{camera.name}: square_mm must be a positive length (mm), got {square_mm}")
    if int(n) < 1:
        raise TranslucencyError(f"{camera.name}: n must be at least 1 photograph, got {n}")
    return nx, ny


def _rotation_about(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation by ``angle`` (radians) about the unit ``axis`` (Rodrigues' formula)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def _quad_area(uv: np.ndarray) -> float:
    """The area (px²) of the quadrilateral through the points (4, 2) in order (the shoelace formula)."""
    x, y = uv[:, 0], uv[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def checkerboard_poses(
    camera: Camera, inner: tuple[int, int], square_mm: float, n: int = 8, seed: int = 0
) -> list[np.ndarray]:
    """``n`` poses (4 × 4, board frame → object frame, mm) of a checkerboard in front of ``camera``.

    ``inner`` = (columns, rows) of inner corners, ``square_mm`` the squares' side.  Each board faces the
    camera tilted by 15°–35° in a direction that turns by 360°/n from pose to pose, covers 30–60 % of the
    picture and lies wholly inside it with a margin (module notes); the same ``seed`` gives the same
    poses.  A board that cannot be so placed (too elongated for the picture) is refused in one line.

    Examples
    --------
    >>> cam = Camera.looking_at((0.0, 0.0, 100.0), (0.0, 0.0, 0.0), 160, 120, fov_deg=40.0)
    >>> poses = checkerboard_poses(cam, (7, 5), 4.0, n=3)
    >>> [p.shape for p in poses]
    [(4, 4), (4, 4), (4, 4)]
    """
    nx, ny = _check_board(camera, inner, square_mm, n)
    s = float(square_mm)
    W, H = camera.width, camera.height
    margin = max(2.0, 0.03 * min(W, H))
    fx, fy = camera.K[0, 0], camera.K[1, 1]
    # the board's outline (its squares' extent) and centre in its own frame, mm
    outline = np.array([[-s, -s, 0.0], [nx * s, -s, 0.0], [nx * s, ny * s, 0.0], [-s, ny * s, 0.0]])
    centre_b = np.array([0.5 * (nx - 1) * s, 0.5 * (ny - 1) * s, 0.0])
    area_mm2 = (nx + 1) * (ny + 1) * s * s
    # the board facing the camera: its x along the picture's right, y up, z towards the camera
    facing = np.diag([1.0, -1.0, -1.0])
    rng = np.random.default_rng(seed)
    poses = []
    for k in range(int(n)):
        phi = 2 * np.pi * k / int(n) + rng.uniform(0.0, 2 * np.pi / int(n))
        for _ in range(_DRAWS):
            tilt = np.radians(rng.uniform(*TILT_DEG))
            roll = np.radians(rng.uniform(-ROLL_DEG, ROLL_DEG))
            fill = rng.uniform(*FILL)
            # board → camera rotation: turned in the picture's plane, then tilted about an in-plane axis
            axis = np.array([np.cos(phi), np.sin(phi), 0.0])
            R_cb = _rotation_about(axis, tilt) @ _rotation_about(np.array([0.0, 0.0, 1.0]), roll) @ facing
            # the distance at which the outline covers ``fill`` of the picture: area·cos(tilt)·f_x f_y / d²
            d = np.sqrt(area_mm2 * np.cos(tilt) * fx * fy / (fill * W * H))
            # the centre's ray: through a pixel drawn near the principal point (a tenth of the picture)
            du, dv = rng.uniform(-0.1, 0.1, 2) * (W, H)
            ray = np.array([du / fx, dv / fy, 1.0])
            p_c = d * ray / np.linalg.norm(ray)
            # camera frame x_c = R_cb (X_b − c_b) + p_c, object frame X = Rᵀ (x_c − t)
            T = np.eye(4)
            T[:3, :3] = camera.R.T @ R_cb
            T[:3, 3] = camera.R.T @ (p_c - R_cb @ centre_b - camera.t)
            corners = outline @ T[:3, :3].T + T[:3, 3]
            if (camera.depth(corners) <= 0).any():
                continue
            uv = camera.project(corners)
            inside = (uv >= margin).all() and (uv <= np.array([W - 1, H - 1]) - margin).all()
            if inside and FILL[0] <= _quad_area(uv) / (W * H) <= FILL[1]:
                poses.append(T)
                break
        else:
            raise TranslucencyError(
                f"{camera.name}: a {nx} x {ny} checkerboard cannot be placed to cover {FILL[0]:.0%}-"
                f"{FILL[1]:.0%} of the {W} x {H} picture"
            )
    return poses


def render_checkerboards(
    camera: Camera,
    inner: tuple[int, int],
    square_mm: float,
    n: int = 8,
    seed: int = 0,
    spp: int = 16,
) -> list[np.ndarray]:
    """Mitsuba photographs (H, W, 3) float32 of a glowing checkerboard in the :func:`checkerboard_poses`
    of ``camera`` (a distortion-free camera with square pixels and a centred principal point, which
    :meth:`.Camera.sensor_dict` renders), ``spp`` samples a pixel, seeds ``seed``, ``seed`` + 1, ….

    Examples
    --------
    >>> from translucency.rig.object.cameras import Camera
    >>> from translucency.rig.object.targets import render_checkerboards
    >>> cam = Camera.looking_at((0.0, 0.0, 100.0), (0.0, 0.0, 0.0), 80, 60, fov_deg=40.0)
    >>> images = render_checkerboards(cam, (7, 5), 4.0, n=2, spp=4)
    >>> images[0].shape, images[0].dtype
    ((60, 80, 3), dtype('float32'))
    """
    if int(spp) < 1:
        raise TranslucencyError(f"{camera.name}: spp must be at least 1 sample a pixel, got {spp}")
    sensor = camera.sensor_dict(int(spp))
    mi = mitsuba()
    photographs = []
    for k, pose in enumerate(checkerboard_poses(camera, inner, square_mm, n, seed)):
        scene = checkerboard_scene(sensor, pose, inner, square_mm)
        image = mi.render(scene, spp=int(spp), seed=int(seed) + k)
        photographs.append(np.array(image, dtype=np.float32))
    return photographs


__all__ = ["FILL", "ROLL_DEG", "TILT_DEG", "checkerboard_poses", "render_checkerboards"]
