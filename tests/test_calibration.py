"""Planar calibration on OpenCV: marked points that cannot fix a homography are refused in one line naming
them; well-spread ones, a checkerboard and bright markers give the pose's homography (the known truth of a
virtual camera) with integer pixel coordinates at pixel centres."""

import json

import numpy as np
import pytest

from translucency._validate import TranslucencyError
from translucency.rig import homography_from_checkerboard, homography_from_points, load_calibration, write_pfm
from translucency.rig.planar.calibration import find_markers
from translucency.rig.planar.photographs import VirtualCamera, homography_error

#: an oblique pose over a 10 × 10 mm sample (as tests/test_rig.py's)
CAMERA = VirtualCamera((5.0, -4.0, 11.0), (5.0, 5.0, 0.0), 40.0, 240, 200)
SQUARE = np.array([[2.0, 2.0], [8.0, 2.0], [8.0, 8.0], [2.0, 8.0]])


def _refused(xy, uv=None, *, match):
    uv = CAMERA.homography().to_image(xy) if uv is None else uv
    with pytest.raises(TranslucencyError, match=match) as err:
        homography_from_points(xy, uv)
    assert len(str(err.value).splitlines()) == 1 and str(err.value).startswith("calibration: ")


# -- marked points that cannot fix a homography --------------------------------------------------------
@pytest.mark.parametrize("off", range(4))
def test_four_points_with_three_on_a_line_are_refused(off):
    """The defect: the 8 × 9 DLT matrix of four points has 8 singular values, and the test for a second
    null direction looked at the 7th — three collinear points were fitted 'to 0.000 px rms'."""
    xy = np.array([[2.0, 2.0], [4.0, 4.0], [6.0, 6.0], [8.0, 8.0]])
    xy[off] = [2.0, 8.0]
    on = ", ".join(str(k + 1) for k in range(4) if k != off)
    _refused(xy, match=f"marked points {on} lie on one line in the sample plane; a homography needs four")


def test_four_points_three_on_a_line_within_the_tolerance_are_refused_and_beyond_it_accepted():
    # the spread (RMS distance from the centroid) of these points is 3 mm; the tolerance is 1 % of it
    for dy, ok in ((0.01, False), (0.5, True)):
        xy = np.array([[2.0, 2.0], [5.0, 5.0 + dy], [8.0, 8.0], [2.0, 8.0]])
        if ok:
            H, rms = homography_from_points(xy, CAMERA.homography().to_image(xy))
            assert homography_error(H, CAMERA.homography(), SQUARE) < 1e-3
        else:
            _refused(xy, match="marked points 1, 2, 3 lie on one line in the sample plane")


def test_three_on_a_line_in_the_image_only_is_refused():
    uv = np.array([[10.0, 10.0], [50.0, 50.0], [90.0, 90.0], [10.0, 90.0]])
    _refused(SQUARE, uv, match="marked points 1, 2, 3 lie on one line in the image")


@pytest.mark.parametrize(
    "case, match",
    [
        ("three", "a homography needs at least 4 marked points, got 3"),
        ("counts", "4 marked points in the sample plane but 5 in the image"),
        ("same_sample", "marked points 2 and 4 coincide in the sample plane"),
        ("same_image", "marked points 1 and 3 coincide in the image"),
        ("all_on_a_line", "all 6 marked points lie on one line in the sample plane"),
        ("all_but_one", "marked points 1, 2, 3, 5, 6, 7 lie on one line in the sample plane"),
        ("clustered", "the 6 marked points fix the homography poorly"),
    ],
)
def test_point_sets_that_cannot_fix_a_homography_are_refused_in_one_line(case, match):
    H = CAMERA.homography()
    xy, uv = SQUARE.copy(), None
    if case == "three":
        xy = SQUARE[:3]
    elif case == "counts":
        uv = np.vstack([H.to_image(SQUARE), [[1.0, 2.0]]])
    elif case == "same_sample":
        xy = np.vstack([SQUARE, [[5.0, 5.0]]])
        xy[3] = xy[1]
    elif case == "same_image":
        uv = H.to_image(SQUARE)
        uv[2] = uv[0]
    elif case == "all_on_a_line":
        xy = np.stack([np.linspace(1, 9, 6), np.linspace(2, 3, 6)], axis=1)
    elif case == "all_but_one":  # seven points: six on a line and one off it
        xy = np.stack([np.linspace(1, 9, 7), np.full(7, 5.0)], axis=1)
        xy[3] = [5.0, 8.0]
    elif case == "clustered":  # three tight pairs: three points, in effect
        xy = np.array([[1.0, 1.0], [1.01, 1.0], [9.0, 1.0], [9.0, 1.01], [5.0, 9.0], [5.01, 9.0]])
    _refused(xy, uv, match=match)


def test_refusals_name_the_calibration_file(tmp_path):
    xy = [[3.0, 3.0], [5.0, 5.0], [7.0, 7.0], [3.0, 8.0]]
    spec = {"points": {"sample_mm": xy, "image_px": CAMERA.homography().to_image(xy).tolist()}, "scale": 1}
    (tmp_path / "cal.json").write_text(json.dumps(spec))
    with pytest.raises(TranslucencyError, match=r"cal\.json: points: marked points 1, 2, 3 lie on one line"):
        load_calibration(tmp_path / "cal.json")


# -- point sets that fix it ----------------------------------------------------------------------------
def test_well_spread_points_give_the_truth_and_the_reprojection_error():
    H = CAMERA.homography()
    a = np.radians(np.arange(8) * 45.0 + 10.0)
    ellipse = np.stack([5 + 4 * np.cos(a), 5 + 3 * np.sin(a)], axis=1)
    grid = np.stack(np.meshgrid(np.arange(3.0, 9.0), np.arange(3.0, 9.0)), axis=-1).reshape(-1, 2)
    for xy in (
        SQUARE,
        ellipse,
        grid,
    ):  # a grid has many collinear triples, and four points in general position
        est, rms = homography_from_points(xy, H.to_image(xy))
        assert rms < 5e-5 and homography_error(est, H, SQUARE) < 5e-5, (len(xy), rms)
    rng = np.random.default_rng(7)
    noisy = H.to_image(grid) + rng.normal(0.0, 0.1, grid.shape)
    est, rms = homography_from_points(grid, noisy)
    assert 0.1 < rms < 0.17  # expected: 0.1 px · √2 (two coordinates) · √(64/72) (8 parameters fitted) = 0.13
    assert homography_error(est, H, [[5.5, 5.5]]) < 0.1


# -- the checkerboard ----------------------------------------------------------------------------------
def board(camera, inner, square_mm, origin_mm, ss=4, noise=0.0, seed=0):
    """A photograph of a checkerboard whose inner corner (i, j) is at origin + square·(i, j) (mm): each
    pixel the mean over ss × ss points of its area (integer coordinates at pixel centres), a white margin
    of one square around the board, grey beyond."""
    H = camera.homography()
    nx, ny = inner
    v, u = np.mgrid[0 : camera.height, 0 : camera.width].astype(float)
    img = np.zeros(u.shape)
    for a in (np.arange(ss) + 0.5) / ss - 0.5:
        for b in (np.arange(ss) + 0.5) / ss - 0.5:
            xy = H.to_sample(np.stack([(u + a).ravel(), (v + b).ravel()], 1))
            q = np.floor((xy - origin_mm) / square_mm).astype(int) + 1  # squares from one before corner 0
            on = (q >= 0).all(1) & (q[:, 0] <= nx) & (q[:, 1] <= ny)
            margin = (q >= -1).all(1) & (q[:, 0] <= nx + 1) & (q[:, 1] <= ny + 1)
            val = np.where(on, (q.sum(1) % 2 == 1) * 0.9 + 0.05, np.where(margin, 0.95, 0.4))
            img += val.reshape(u.shape) / ss**2
    return img + noise * np.random.default_rng(seed).standard_normal(img.shape)


#: the outer inner corners of the 7 × 4 board of 0.8 mm squares used below, mm
BOARD_CORNERS = [[2.5, 3.5], [7.3, 3.5], [7.3, 5.9], [2.5, 5.9]]


def test_checkerboard_gives_the_truth_on_a_board_that_is_not_square():
    H = CAMERA.homography()
    img = board(CAMERA, (7, 4), 0.8, (2.5, 3.5))
    est, rms = homography_from_checkerboard(img, (7, 4), 0.8, origin_mm=(2.5, 3.5))
    assert rms < 0.15 and homography_error(est, H, BOARD_CORNERS) < 0.15, (
        rms,
        homography_error(est, H, BOARD_CORNERS),
    )
    # with noise (5 % of the contrast per pixel) the corners still land within a quarter of a pixel
    est, rms = homography_from_checkerboard(
        board(CAMERA, (7, 4), 0.8, (2.5, 3.5), noise=0.05), (7, 4), 0.8, (2.5, 3.5)
    )
    assert homography_error(est, H, BOARD_CORNERS) < 0.25


def test_checkerboard_labelling_is_the_one_with_x_left_to_right():
    """Seen from the far side (the camera turned 180° about z) the board's x axis runs right to left: the
    labelling chosen is the board turned by 180°, which runs left to right."""
    cam = VirtualCamera((5.0, 14.0, 11.0), (5.0, 5.0, 0.0), 40.0, 240, 200)
    nx, ny, s, o = 7, 4, 0.8, np.array([2.5, 3.5])
    est, _ = homography_from_checkerboard(board(cam, (nx, ny), s, o), (nx, ny), s, origin_mm=o)
    ij = np.stack(np.meshgrid(np.arange(nx), np.arange(ny)), axis=-1).reshape(-1, 2)
    turned = o + s * ([nx - 1, ny - 1] - ij)
    err = np.linalg.norm(est.to_image(o + s * ij) - cam.homography().to_image(turned), axis=1).max()
    assert err < 0.2
    J = est.jacobian([o + s * np.array([nx - 1, ny - 1]) / 2])[0]
    assert np.linalg.det(J) < 0 and J[0, 0] > 0  # seen from above; x to the right in the image


def test_checkerboard_not_found_is_one_line():
    img = board(CAMERA, (7, 4), 0.8, (2.5, 3.5))
    with pytest.raises(TranslucencyError, match="checkerboard: OpenCV finds no 6 x 5 grid of inner corners"):
        homography_from_checkerboard(img, (6, 5), 0.8)
    with pytest.raises(TranslucencyError, match="need at least 2 x 2 inner corners"):
        homography_from_checkerboard(img, (1, 4), 0.8)


def test_checkerboard_calibration_file(tmp_path):
    img = board(CAMERA, (7, 4), 0.8, (2.5, 3.5)).astype(np.float32)
    write_pfm(tmp_path / "board.pfm", np.repeat(img[..., None], 3, axis=2))
    spec = {
        "checkerboard": {"image": "board.pfm", "inner": [7, 4], "square_mm": 0.8, "origin_mm": [2.5, 3.5]}
    }
    (tmp_path / "cal.json").write_text(json.dumps({**spec, "scale": 1.0}))
    calib = load_calibration(tmp_path / "cal.json")
    assert calib.source["method"] == "checkerboard" and calib.source["rms_px"] < 0.15
    assert homography_error(calib.homography, CAMERA.homography(), BOARD_CORNERS) < 0.15
    spec["checkerboard"]["inner"] = [6, 5]
    (tmp_path / "cal.json").write_text(json.dumps({**spec, "scale": 1.0}))
    with pytest.raises(TranslucencyError, match=r"cal\.json: checkerboard board\.pfm: OpenCV finds no 6 x 5"):
        load_calibration(tmp_path / "cal.json")


# -- the pixel convention ------------------------------------------------------------------------------
def test_integer_pixel_coordinates_are_pixel_centres():
    """A marker centred on pixel [row 12, col 20] is found at (u, v) = (20, 12), as OpenCV counts."""
    v, u = np.mgrid[0:40, 0:50].astype(float)
    img = np.exp(-((u - 20.0) ** 2 + (v - 12.0) ** 2) / 2.0)
    assert np.allclose(find_markers(img, 1, threshold=0.01), [[20.0, 12.0]], atol=1e-9)
