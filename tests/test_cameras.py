"""Calibrated cameras (rig.object.cameras) and the virtual checkerboards that calibrate them
(rig.object.targets), against truths found another way: where Mitsuba renders a glowing sphere, the
solid angle of a rectangular field in closed form (and of a distorted one by quadrature of the lens
model), a known pose and known intrinsics recovered by OpenCV, and every refusal in one line naming the
camera."""

import json

import numpy as np
import pytest

from translucency._validate import TranslucencyError
from translucency.mitsuba import mitsuba
from translucency.rig.object.cameras import Camera, calibrate_intrinsics, estimate_pose
from translucency.rig.object.targets import FILL, TILT_DEG, checkerboard_poses, render_checkerboards
from translucency.rig.shared.checkerboard import find_corners

#: a lens with radial and tangential distortion (OpenCV's k1, k2, p1, p2, k3)
LENS = [-0.1, 0.01, 0.001, -0.0005, 0.0]


def _one_line(excinfo, name: str) -> str:
    """The refusal's message, checked to be one line that names the camera once."""
    msg = str(excinfo.value)
    assert "\n" not in msg and msg.count(name) == 1, msg
    return msg


def _lens_camera(width, height, fov_deg, name="cam B") -> Camera:
    """An oblique camera with ``LENS`` and its principal point off the image centre."""
    cam = Camera.looking_at((35.0, -70.0, 45.0), (2.0, 3.0, -1.0), width, height, fov_deg=fov_deg)
    K = cam.K + np.array([[0.0, 0.0, 0.04 * width], [0.0, 0.0, -0.03 * height], [0.0, 0.0, 0.0]])
    return Camera(K, LENS, cam.R, cam.t, width, height, name)


# -- projection against Mitsuba --------------------------------------------------------------------------


def test_project_agrees_with_where_mitsuba_renders_a_glowing_sphere():
    """The centroid of each glowing sphere's image, through ``sensor_dict``, is where ``project`` puts the
    sphere's ellipse: on a pinhole the image of a sphere of angular radius ρ seen α off the axis spans
    tan(α ± ρ) along its radial line, so its centre is ((tan(α+ρ) + tan(α−ρ))/2) f from the principal
    point, slightly beyond the projected centre (f tan α)."""
    W, H = 64, 40
    cam = Camera.looking_at((35.0, -70.0, 45.0), (2.0, 3.0, -1.0), W, H, fov_deg=50.0, up=(0.3, 0.1, 1.0))
    f, c = cam.K[0, 0], cam.K[:2, 2]
    radius = 3.0
    # four spheres spread over the picture, ≈ 26 px from the principal point (a 0.2 % error of f: 0.05 px)
    o, d, _ = cam.pixel_rays()
    pixels = [(8, 7), (56, 8), (9, 33), (55, 32)]
    centres = [o[v * W + u] + 88.0 * d[v * W + u] for u, v in pixels]
    scene = {"type": "scene", "integrator": {"type": "direct"}, "camera": cam.sensor_dict(256)}
    for k, X in enumerate(centres):
        scene[f"ball{k}"] = {
            "type": "sphere",
            "center": X.tolist(),
            "radius": radius,
            "bsdf": {"type": "diffuse", "reflectance": 0.0},
            "emitter": {"type": "area", "radiance": 1.0},
        }
    mi = mitsuba()
    image = np.array(mi.render(mi.load_dict(scene), seed=1), dtype=np.float64)[..., 0]
    rows, cols = np.indices(image.shape)
    for X in centres:
        uv = cam.project([X])[0]
        # the ellipse's centre along the radial line (normalised units → pixels)
        x_c = cam.R @ X + cam.t
        tan_a = np.hypot(x_c[0], x_c[1]) / x_c[2]
        alpha, rho = np.arctan(tan_a), np.arcsin(radius / np.linalg.norm(x_c))
        shift = 0.5 * (np.tan(alpha + rho) + np.tan(alpha - rho)) - tan_a
        expected = uv + f * shift * (uv - c) / np.linalg.norm(uv - c)
        window = (np.abs(cols - expected[0]) <= 6) & (np.abs(rows - expected[1]) <= 6)
        ring = window & ~((np.abs(cols - expected[0]) <= 5) & (np.abs(rows - expected[1]) <= 5))
        assert image[ring].max() == 0.0  # the whole disc lies in its window
        w = image * window
        centroid = np.array([(w * cols).sum(), (w * rows).sum()]) / w.sum()
        assert np.linalg.norm(centroid - expected) < 0.05, (centroid, expected, uv)  # 0.01 px of noise
        assert 0.01 < np.linalg.norm(expected - uv) < 0.1  # the shift is real and small


def test_sensor_dict_refuses_a_camera_mitsuba_cannot_render():
    with pytest.raises(TranslucencyError) as excinfo:
        _lens_camera(40, 30, 50.0).sensor_dict(4)
    assert "distortion-free" in _one_line(excinfo, "cam B")


# -- pixel rays ------------------------------------------------------------------------------------------


def test_pixel_rays_pass_through_the_points_that_project_onto_their_pixels():
    cam = _lens_camera(48, 36, 70.0)
    o, d, omega = cam.pixel_rays()
    assert o.shape == d.shape == (48 * 36, 3) and omega.shape == (48 * 36,)
    np.testing.assert_allclose(o, np.broadcast_to(cam.centre, o.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)
    v, u = np.mgrid[0:36, 0:48]
    centres = np.stack([u.ravel(), v.ravel()], axis=1)
    for s in (10.0, 250.0):
        assert np.abs(cam.project(o + s * d) - centres).max() < 1e-6
    assert (cam.depth(o + 10.0 * d) > 0).all()


def test_pixel_solid_angles_sum_to_the_field_of_view_in_closed_form():
    """A rectangular field of half-angles a, b (tan a = (W/2)/f_x) subtends 4 asin(sin a sin b)."""
    cam = Camera.looking_at((35.0, -70.0, 45.0), (2.0, 3.0, -1.0), 48, 30, fov_deg=70.0)
    _, _, omega = cam.pixel_rays()
    a, b = np.arctan(24 / cam.K[0, 0]), np.arctan(15 / cam.K[1, 1])
    truth = 4 * np.arcsin(np.sin(a) * np.sin(b))
    assert abs(omega.sum() / truth - 1) < 0.01


def test_pixel_solid_angles_of_a_distorted_lens_sum_to_its_field_by_quadrature():
    """The field of a distorted lens: the directions (x, y, 1) whose image ``project`` puts inside the
    picture, integrated over a fine grid of the plane z_c = 1 with dΩ = (1 + x² + y²)^(−3/2) dx dy."""
    cam = _lens_camera(48, 36, 70.0)
    _, _, omega = cam.pixel_rays()
    level = cam.with_pose(np.eye(3), np.zeros(3))  # camera frame = object frame
    h = 1.6e-3
    x, y = np.meshgrid(np.arange(-0.9, 0.9, h) + h / 2, np.arange(-0.7, 0.7, h) + h / 2)
    uv = level.project(np.column_stack([x.ravel(), y.ravel(), np.ones(x.size)]))
    inside = (uv >= -0.5).all(axis=1) & (uv[:, 0] <= 47.5) & (uv[:, 1] <= 35.5)
    assert not inside.reshape(x.shape)[[0, -1]].any() and not inside.reshape(x.shape)[:, [0, -1]].any()
    truth = np.sum((1 + x.ravel() ** 2 + y.ravel() ** 2)[inside] ** -1.5) * h * h
    undistorted = Camera(cam.K, None, cam.R, cam.t, 48, 36).pixel_rays()[2].sum()
    assert abs(omega.sum() / truth - 1) < 0.01
    assert abs(undistorted / truth - 1) > 0.03  # the lens changes the field: the test can tell


def test_a_lens_model_that_folds_inside_the_image_is_refused():
    cam = Camera.looking_at((0.0, 0.0, 100.0), (0.0, 0.0, 0.0), 40, 30, fov_deg=100.0)
    with pytest.raises(TranslucencyError) as excinfo:
        Camera(cam.K, [-0.1, 0, 0, 0, 0], cam.R, cam.t, 40, 30, "cam F").pixel_rays()
    assert "cannot be inverted" in _one_line(excinfo, "cam F")


# -- pose from marked points -----------------------------------------------------------------------------


def _pose_case(noise_px, n=12, seed=3):
    """A 1920 × 1440 camera with ``LENS`` 100 mm from 12 points spread over 48 × 34 × 50 mm in front of it
    (all in the picture), their projections with Gaussian noise, and the camera with the same intrinsics
    but another pose."""
    target = np.array([2.0, 3.0, -1.0])
    origin = target + 100.0 * np.array([33.0, -73.0, 46.0]) / np.linalg.norm([33.0, -73.0, 46.0])
    cam = Camera.looking_at(origin, target, 1920, 1440, fov_deg=40.0)
    K = cam.K + np.array([[0.0, 0.0, 30.0], [0.0, 0.0, -20.0], [0.0, 0.0, 0.0]])
    cam = Camera(K, LENS, cam.R, cam.t, 1920, 1440, "cam P")
    rng = np.random.default_rng(seed)
    x_c = rng.uniform([-24.0, -17.0, 75.0], [24.0, 17.0, 125.0], (n, 3))
    X = (x_c - cam.t) @ cam.R  # Rᵀ (x_c − t)
    uv = cam.project(X)
    assert (uv > 0).all() and (uv < [1919, 1439]).all()
    return cam, cam.with_pose(np.eye(3), [0.0, 0.0, 100.0]), X, uv + rng.normal(0.0, noise_px, (n, 2))


def test_estimate_pose_recovers_a_known_pose_from_noisy_marks():
    truth, guess, X, uv = _pose_case(0.2)
    posed, rms = estimate_pose(guess, X, uv)
    turn = np.degrees(np.arccos(np.clip((np.trace(posed.R.T @ truth.R) - 1) / 2, -1.0, 1.0)))
    assert turn < 0.1
    assert np.linalg.norm(posed.centre - truth.centre) < 0.1
    assert 0.12 < rms < 0.4  # √2·0.2 px·√(18/24) = 0.245 px expected (6 of 24 coordinates fitted)
    np.testing.assert_array_equal(posed.K, truth.K)


@pytest.mark.parametrize(
    "case, match",
    [
        ("few", "at least 6 marked points, got 5"),
        ("counts", "12 marked points but 11 pixel positions"),
        ("noisy", r"fits the marked points to [0-9.]+ px rms \(> 1 px\)"),
        ("behind", "behind the camera"),
    ],
)
def test_estimate_pose_refusals_are_one_line_naming_the_camera(case, match):
    truth, guess, X, uv = _pose_case(2.0 if case == "noisy" else 0.0)
    if case == "few":
        X, uv = X[:5], uv[:5]
    elif case == "counts":
        uv = uv[:11]
    elif case == "behind":  # four points mirrored through the camera centre, marked where they project
        X = np.concatenate([X, 2 * truth.centre - X[:4]])
        uv = truth.project(X)
        assert (truth.depth(X) < 0).sum() == 4
    with pytest.raises(TranslucencyError, match=match) as excinfo:
        estimate_pose(guess, X, uv, max_rms_px=1.0)
    _one_line(excinfo, "cam P")


# -- the virtual checkerboards and intrinsics from them --------------------------------------------------

INNER, SQUARE_MM = (7, 5), 4.0


@pytest.fixture(scope="module")
def boards():
    """A 240 × 180 px camera and eight Mitsuba photographs of a 7 × 5 board in its checkerboard poses."""
    cam = Camera.looking_at((40.0, -90.0, 60.0), (0.0, 0.0, 0.0), 240, 180, fov_deg=45.0, name="cam C")
    return cam, checkerboard_poses(cam, INNER, SQUARE_MM), render_checkerboards(cam, INNER, SQUARE_MM, spp=32)


def _board_points(inner, square_mm):
    k = np.arange(inner[0] * inner[1])
    return np.column_stack([(k % inner[0]) * square_mm, (k // inner[0]) * square_mm, np.zeros(k.size)])


def test_checkerboard_poses_face_the_camera_tilted_and_fill_the_picture(boards):
    cam, poses, _ = boards
    W, H = cam.width, cam.height
    s = SQUARE_MM
    outline = np.array([[-s, -s, 0], [7 * s, -s, 0], [7 * s, 5 * s, 0], [-s, 5 * s, 0]])  # the squares
    azimuths = []
    for T in poses:
        np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
        normal_c = cam.R @ T[:3, 2]  # the board's +z in the camera frame
        tilt = np.degrees(np.arccos(-normal_c[2]))
        assert TILT_DEG[0] - 1e-9 <= tilt <= TILT_DEG[1] + 1e-9
        azimuths.append(np.degrees(np.arctan2(normal_c[1], normal_c[0])) % 360)
        uv = cam.project(outline @ T[:3, :3].T + T[:3, 3])
        assert (uv > 2).all() and (uv[:, 0] < W - 3).all() and (uv[:, 1] < H - 3).all()
        x, y = uv[:, 0], uv[:, 1]
        fill = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))) / (W * H)
        assert FILL[0] <= fill <= FILL[1]
    # tilted in varied directions: one in each eighth of the turn
    assert sorted(np.floor(np.array(azimuths) / 45).astype(int).tolist()) == list(range(8))
    again = checkerboard_poses(cam, INNER, SQUARE_MM)
    np.testing.assert_array_equal(np.array(again), np.array(poses))  # the same seed, the same poses


def test_checkerboard_photographs_show_the_board_where_the_camera_projects_it(boards):
    """Corners found by OpenCV lie at the projected inner corners; square (a, b) is white iff a + b is
    even, seen at its projected centre."""
    cam, poses, images = boards
    corners = _board_points(INNER, SQUARE_MM)
    a, b = np.meshgrid(np.arange(INNER[0] + 1), np.arange(INNER[1] + 1))
    middles = np.column_stack(
        [(a.ravel() - 0.5) * SQUARE_MM, (b.ravel() - 0.5) * SQUARE_MM, np.zeros(a.size)]
    )
    white = (a.ravel() + b.ravel()) % 2 == 0
    for T, image in zip(poses, images, strict=True):
        assert image.shape == (180, 240, 3) and image.dtype == np.float32
        truth = cam.project(corners @ T[:3, :3].T + T[:3, 3])
        found = find_corners(image, INNER)
        err = np.linalg.norm(found[:, None] - truth[None], axis=2).min(axis=1)
        assert err.max() < 0.5 and np.sqrt(np.mean(err**2)) < 0.2  # cornerSubPix: ≈ 0.1 px rms here
        uv = np.round(cam.project(middles @ T[:3, :3].T + T[:3, 3])).astype(int)
        seen = image[uv[:, 1], uv[:, 0], 0]
        np.testing.assert_array_equal(seen > 0.5, white)
        assert np.all((seen == 0) | (seen == 1))


def test_calibrate_intrinsics_recovers_a_known_camera_from_its_checkerboards(boards):
    """f within 1 % with p1, p2 free; holding them at 0 (the virtual lens has none) pins the principal
    point within 1 px (free, it trades off against p1, p2: ≈ 1-1.5 px off on these eight photographs)."""
    cam, _, images = boards
    f, c = np.diag(cam.K)[:2], cam.K[:2, 2]
    for zero_tangent in (False, True):
        K, dist, rms = calibrate_intrinsics(images, INNER, SQUARE_MM, name="cam C", zero_tangent=zero_tangent)
        assert np.abs(np.diag(K)[:2] / f - 1).max() < 0.01
        assert rms < 0.5
        assert dist.shape == (5,) and dist[4] == 0.0
    assert np.abs(K[:2, 2] - c).max() < 1.0
    assert dist[2] == dist[3] == 0.0


def test_calibrate_intrinsics_refusals_are_one_line_naming_the_camera(boards):
    _, _, images = boards
    with pytest.raises(TranslucencyError, match="at least 3 checkerboard photographs, got 2") as excinfo:
        calibrate_intrinsics(images[:2], INNER, SQUARE_MM, name="cam C")
    _one_line(excinfo, "cam C")
    cropped = [images[0], images[1][:, :200], images[2]]
    with pytest.raises(
        TranslucencyError, match=r"photograph 1 is \(180, 200\), the first \(180, 240\)"
    ) as excinfo:
        calibrate_intrinsics(cropped, INNER, SQUARE_MM, name="cam C")
    _one_line(excinfo, "cam C")


def test_targets_refuse_bad_boards_in_one_line():
    cam = Camera.looking_at((0.0, 0.0, 100.0), (0.0, 0.0, 0.0), 80, 60, fov_deg=40.0, name="cam T")
    for inner, square, match in [((1, 5), 4.0, "at least 2 x 2"), ((7, 5), -1.0, "positive length"),
                                 ((40, 2), 4.0, "cannot be placed")]:  # fmt: skip
        with pytest.raises(TranslucencyError, match=match) as excinfo:
            checkerboard_poses(cam, inner, square)
        _one_line(excinfo, "cam T")


# -- camera files ----------------------------------------------------------------------------------------


def test_camera_dict_round_trip_through_json_and_from_a_rodrigues_vector():
    import cv2  # the Rodrigues vector of the truth, independently of rig.object.cameras

    cam = _lens_camera(64, 48, 50.0)
    back = Camera.from_dict(json.loads(json.dumps(cam.to_dict())), name="cam B")
    for key in ("K", "dist", "R", "t"):
        np.testing.assert_array_equal(getattr(back, key), getattr(cam, key))
    assert (back.width, back.height, back.name) == (64, 48, "cam B")
    d = cam.to_dict()
    d["rvec"] = cv2.Rodrigues(cam.R)[0].ravel().tolist()
    del d["R"]
    np.testing.assert_allclose(Camera.from_dict(d).R, cam.R, atol=1e-12)


@pytest.mark.parametrize(
    "change, match",
    [
        (lambda d: d.pop("K"), "missing 'K'"),
        (lambda d: d.pop("R"), r"missing 'R' \(or 'rvec'\)"),
        (lambda d: d.update(R=(2 * np.eye(3)).tolist()), "R must be a 3 x 3 rotation"),
        (lambda d: d.update(R=np.diag([1.0, 1.0, -1.0]).tolist()), "R must be a 3 x 3 rotation"),
        (lambda d: d.update(K=[[1.0, 0.0], [0.0, 1.0]]), "K must be a finite 3 x 3"),
        (lambda d: d.update(width="wide"), "not a camera"),
    ],
)
def test_bad_camera_dicts_are_refused_in_one_line(change, match):
    d = _lens_camera(64, 48, 50.0).to_dict()
    change(d)
    with pytest.raises(TranslucencyError, match=match) as excinfo:
        Camera.from_dict(d, name="cam D")
    _one_line(excinfo, "cam D")
