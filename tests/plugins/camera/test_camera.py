"""Camera family: model, decomposition, distortion, corners, calibration, against known truth."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins.camera import (
    board_corners,
    calibrate_board,
    calibrate_dlt,
    decompose,
    distort_image,
    distort_pixels,
    pinhole,
    project,
    projection,
    undistort_image,
    undistort_pixels,
    undistort_points,
    vanishing_points,
)
from graphvision_plugins.synthetic import board_views, plane_lines, plane_view

from ...conftest import PIPELINES

K_REF = np.array([[500.0, 0, 320.0], [0, 520.0, 240.0], [0, 0, 1]])
DIST_REF = np.array([-0.3, 0.1, 0.001, -0.002, -0.02])


@pytest.fixture(scope="module")
def boards():
    return board_views(views=4, width=480, height=360, focal=600, noise=0.02, seed=3)


def random_camera(rng: np.random.Generator) -> gv.PinholeCamera:
    return pinhole(
        fx=rng.uniform(300, 1500),
        fy=rng.uniform(300, 1500),
        cx=rng.uniform(200, 400),
        cy=rng.uniform(150, 300),
        skew=rng.uniform(-5, 5),
        rotation=tuple(rng.uniform(-1, 1, 3)),
        centre=tuple(rng.uniform(-10, 10, 3)),
    )


@pytest.mark.parametrize("seed", range(5))
def test_decomposition_recovers_k_r_c_of_a_random_camera(seed):
    truth = random_camera(np.random.default_rng(seed))
    scale = np.random.default_rng(seed + 100).uniform(-3, 3)  # P is known up to scale and sign
    found = decompose(projection(truth) * scale)
    np.testing.assert_allclose(found.K, truth.K, atol=1e-9 * truth.K.max())
    np.testing.assert_allclose(found.R, truth.R, atol=1e-9)
    np.testing.assert_allclose(found.C, truth.C, atol=1e-9)
    assert np.linalg.det(found.R) == pytest.approx(1.0)


def test_projection_matches_p_times_x_for_a_pinhole():
    camera = random_camera(np.random.default_rng(7))
    points = (
        camera.C
        + (np.random.default_rng(8).uniform(-1, 1, (20, 3)) + np.array([0, 0, 5])) @ camera.R
    )
    xh = np.column_stack([points, np.ones(20)]) @ camera.P.T
    np.testing.assert_allclose(project(camera, points), xh[:, :2] / xh[:, 2:], atol=1e-8)


def test_project_refuses_points_behind_the_camera():
    camera = pinhole()
    with pytest.raises(ValueError, match="1 of 2 points lie behind the camera"):
        project.__wrapped__(camera, np.array([[0.0, 0, 5], [0, 0, -5]]))


def test_undistort_points_equals_opencv_run_to_convergence():
    points = np.array([[10.0, 20.0], [630.0, 470.0], [320.0, 240.0], [100.0, 400.0]])
    # cv2.undistortPoints(points[:, None], K_REF, DIST_REF, R=None, P=K_REF,
    #     criteria=(COUNT | EPS, 100, 1e-12)) with OpenCV 5.0.0; its default criteria
    # (5 iterations) stop 0.75 px away at the corner (10, 20)
    opencv = np.array(
        [
            [-64.755314981, -34.3845798506],
            [714.3522609528, 531.0868251503],
            [320.0, 240.0],
            [78.5212004067, 415.7001100125],
        ]
    )
    camera = gv.PinholeCamera(K_REF.copy(), distortion=DIST_REF.copy())
    found = undistort_points(camera, points)
    np.testing.assert_allclose(found, opencv, atol=1e-4)
    np.testing.assert_allclose(distort_pixels(found, K_REF, DIST_REF), points, atol=1e-6)


def test_undistortion_map_equals_opencv():
    # cv2.initUndistortRectifyMap(K_REF, DIST_REF, None, K_REF, (640, 480), cv2.CV_32FC1)
    # at pixels (0, 0), (639, 479), (100, 400), (600, 30), OpenCV 5.0.0 (float32 maps)
    pixels = np.array([[0.0, 0], [639, 479], [100, 400], [600, 30]])
    opencv = np.array(
        [
            [47.764678955078125, 36.614234924316406],
            [589.3773193359375, 442.60662841796875],
            [116.49242401123047, 387.9457702636719],
            [564.3838500976562, 56.60248565673828],
        ]
    )
    np.testing.assert_allclose(distort_pixels(pixels, K_REF, DIST_REF), opencv, atol=1e-4)


def test_undistort_image_inverts_distort_image_on_a_smooth_image():
    v, u = np.mgrid[0:96, 0:128] / 128.0
    image = (0.5 + 0.4 * np.sin(6 * u) * np.cos(5 * v)).astype(np.float32)
    lens = pinhole(fx=100, fy=100, cx=63.5, cy=47.5, k1=-0.2, width=128, height=96)
    restored = undistort_image(distort_image(image, lens), lens)
    inner = (slice(20, 76), slice(25, 103))
    assert np.abs(restored[inner] - image[inner]).max() < 0.01


def test_undistortion_that_cannot_converge_is_refused():
    # r_d = r (1 − 0.5 r²) is at most 0.544 (at r = 0.816): r_d = 0.7 has no preimage
    camera = gv.PinholeCamera(np.eye(3), distortion=np.array([-0.5, 0, 0, 0, 0]))
    with pytest.raises(ValueError, match="undistortion did not converge for 1 of 2 points"):
        undistort_pixels(np.array([[0.1, 0.0], [0.7, 0.0]]), camera.K, camera.distortion)


def test_singular_k_and_negative_focal_are_refused():
    singular = gv.PinholeCamera(np.diag([0.0, 500.0, 1.0]))
    with pytest.raises(ValueError, match=r"K is singular \(fx = 0"):
        undistort_points.__wrapped__(singular, np.zeros((1, 2)))
    with pytest.raises(gv.ParameterError, match="fx"):
        pinhole(fx=-800)


def _dlt_scene(count: int, seed: int, noise: float = 0.2):
    rng = np.random.default_rng(seed)
    truth = pinhole(fx=800, fy=780, cx=330, cy=245, rotation=(0.1, -0.2, 0.05), centre=(1, 2, -8))
    world = rng.uniform(-3, 3, (count, 3)) + np.array([1, 2, 0])  # a 6-unit cube 8 units away
    image = project(truth, world) + rng.normal(0, noise, (count, 2))
    return truth, world, image


@pytest.mark.parametrize("seed", range(3))
def test_dlt_calibration_within_1_5_px_of_the_truth(seed):
    truth, world, image = _dlt_scene(100, seed=seed)
    found = calibrate_dlt(world, image)
    for i, j in [(0, 0), (1, 1), (0, 2), (1, 2)]:
        assert abs(found.camera.K[i, j] - truth.K[i, j]) < 1.5, (i, j)
    assert found.reprojection_rms < 0.3  # 0.2 px noise per coordinate: √2·0.2 ≈ 0.28


def test_dlt_refuses_coplanar_and_too_few_points():
    truth, world, image = _dlt_scene(20, seed=1)
    flat = world.copy()
    flat[:, 2] = 0.0
    with pytest.raises(ValueError, match="coplanar"):
        calibrate_dlt.__wrapped__(flat, project(truth, flat))
    with pytest.raises(ValueError, match="at least 6 correspondences, got 5"):
        calibrate_dlt.__wrapped__(world[:5], image[:5])


def test_board_corners_within_0_1_px_of_the_truth(boards):
    found = board_corners(boards.views)
    assert found.found.all()
    error = np.linalg.norm(found.corners - boards.corners, axis=2)
    assert error.mean() < 0.1
    assert error.max() < 0.5  # every corner labelled in the right order


def test_board_corner_order_is_fixed_under_a_half_turn(boards):
    turned = boards.views[:1, ::-1, ::-1].copy()
    found = board_corners(turned).corners[0]
    h, w = boards.views.shape[1:]
    expected = np.array([w - 1, h - 1]) - boards.corners[0]
    assert np.linalg.norm(found - expected, axis=1).max() < 0.5


def test_view_without_board_is_skipped_and_too_few_views_are_named(boards):
    found = board_corners(boards.views)
    blank = np.full_like(boards.views[:1], 0.5)
    with pytest.warns(
        UserWarning, match=r"no board of 9×6 inner corners found in 1 of 5 views: \[0\]"
    ):
        with_blank = board_corners(np.concatenate([blank, boards.views]))
    assert not with_blank.found[0] and with_blank.found[1:].all()
    calibration = calibrate_board(with_blank.corners, boards.object_points)
    np.testing.assert_array_equal(calibration.views_used, [1, 2, 3, 4])
    corners = found.corners.copy()
    corners[[0, 2]] = np.nan
    with pytest.raises(ValueError, match=r"only 2 of 4 views have a board.*views \[0, 2\]"):
        calibrate_board.__wrapped__(corners, boards.object_points)


def test_calibrate_pipeline_recovers_the_rendering_camera():
    out = gv.run(gv.load_pipeline(PIPELINES / "calibrate.yaml")).outputs
    assert out["focal_error_percent"] <= 0.2
    assert abs(out["distortion"][0] - (-0.1)) <= 0.005
    assert out["reprojection_rms"] <= 0.3
    assert abs(out["K"][0, 2] - out["true_camera"].K[0, 2]) < 2.0
    corner_error = np.linalg.norm(out["corners"] - out["true_corners"], axis=2)
    assert corner_error.mean() <= 0.1
    assert out["corners_drawn"].shape == (480, 640, 3)


def test_undistort_pipeline_residual_is_only_resampling():
    out = gv.run(gv.load_pipeline(PIPELINES / "undistort.yaml")).outputs
    # bilinear resampling twice of the camera image: well under 5 % rms; a wrong
    # inverse (e.g. 5 fixed-point iterations) leaves a misalignment of whole pixels
    assert out["residual_rms"] < 0.05
    assert out["undistorted"].shape == (512, 512)


def test_vanishing_point_of_noise_free_segments_is_exact():
    scene = plane_lines(noise=0.0, seed=4)
    found = vanishing_points(scene.segments, scene.family)
    for estimated, truth in zip(found, scene.vanishing_points, strict=True):
        assert abs(abs(estimated @ truth) - 1) < 1e-12  # the same homogeneous point


def test_vanishing_pipeline_within_half_a_degree_of_the_true_directions():
    out = gv.run(gv.load_pipeline(PIPELINES / "vanishing.yaml")).outputs
    assert out["vanishing_point_error_degrees"] < 0.5
    assert out["horizon_error_degrees"] < 0.5
    # the horizon passes through both true vanishing points
    assert (
        np.abs(out["true_vanishing_points"] @ out["horizon"]).max()
        < 1e-3 * np.abs(out["horizon"]).sum()
    )
    assert out["drawing"].shape == (480, 640, 3)


def test_vanishing_points_refuse_a_family_of_one_segment_and_a_point_segment():
    segments = np.array([[0.0, 0, 10, 10], [0, 10, 10, 20], [0, 0, 10, 0]])
    with pytest.raises(ValueError, match="family 1 has 1 segment"):
        vanishing_points.__wrapped__(segments, np.array([0, 0, 1]))
    segments[2] = [5, 5, 5, 5]
    with pytest.raises(ValueError, match="coincident end points"):
        vanishing_points.__wrapped__(segments, np.array([0, 0, 0]))


def test_too_few_views_in_a_pipeline_fail_naming_the_node():
    graph = gv.load_pipeline(PIPELINES / "calibrate.yaml")
    with pytest.raises(gv.RunError) as failure:
        gv.run(graph, overrides={"boards.views": 2}, outputs=["K"])
    message = str(failure.value.failures)
    assert "calib" in message and "only 2 of 2 views have a board, need 3" in message


def test_plane_view_through_a_fronto_parallel_camera_is_the_texture():
    texture = np.random.default_rng(5).uniform(0, 1, (48, 64)).astype(np.float32)
    # K maps the plane Z = 0 seen from distance 100 with f = 100: one pixel per unit
    camera = pinhole(
        fx=100, fy=100, cx=31.5, cy=23.5, centre=(31.5, 23.5, -100), width=64, height=48
    )
    np.testing.assert_allclose(plane_view(texture, camera), texture, atol=1e-5)


def test_undistorting_a_distorted_plane_view_gives_the_pinhole_view():
    y, x = np.mgrid[0:120, 0:160] / 160.0
    texture = (0.5 + 0.4 * np.sin(9 * x) * np.cos(7 * y)).astype(np.float32)
    pose = {"rotation": (0.2, -0.1, 0.05), "centre": (80, 60, -150), "width": 160, "height": 120}
    # scale 2: the texture spans 320 × 240 units, beyond what the camera sees
    ideal = plane_view(texture, pinhole(fx=150, fy=150, cx=79.5, cy=59.5, **pose), scale=2)
    lens = pinhole(fx=150, fy=150, cx=79.5, cy=59.5, k1=-0.2, k2=0.05, **pose)
    restored = undistort_image(plane_view(texture, lens, scale=2), lens)
    inner = (slice(25, 95), slice(30, 130))
    assert np.abs(restored[inner] - ideal[inner]).max() < 0.02


def test_negative_focal_camera_and_singular_p_are_refused():
    mirrored = gv.PinholeCamera(np.diag([-500.0, 500.0, 1.0]))
    with pytest.raises(ValueError, match="focal lengths must be positive, got fx = -500"):
        project.__wrapped__(mirrored, np.array([[0.0, 0, 5]]))
    with pytest.raises(ValueError, match="singular: P is not a finite camera"):
        decompose.__wrapped__(np.hstack([np.ones((3, 3)), np.ones((3, 1))]))
    with pytest.raises(ValueError, match="must be a finite 3×4 matrix"):
        decompose.__wrapped__(np.eye(3))
