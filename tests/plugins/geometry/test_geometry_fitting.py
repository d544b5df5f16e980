"""Homographies, RANSAC and line fits against synthetic ground truth."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins import fitting, geometry, synthetic

H_TRUE = np.array([[0.9, -0.2, 30.0], [0.15, 1.1, -12.0], [2e-4, -1e-4, 1.0]])


def grid_points(count=50, seed=0):
    return np.random.default_rng(seed).uniform(0, 500, (count, 2))


def keypoints(xy):
    n = len(xy)
    return gv.KeypointSet(np.asarray(xy, float), np.ones(n), np.zeros(n), np.ones(n))


def identity_matches(n):
    return gv.MatchSet(np.column_stack([np.arange(n), np.arange(n)]).astype(np.int64), np.zeros(n))


def test_dlt_recovers_a_known_homography_exactly():
    src = grid_points()
    dst = geometry.apply_homography(H_TRUE, src)
    np.testing.assert_allclose(geometry.estimate_homography(src, dst), H_TRUE, atol=1e-8)
    np.testing.assert_allclose(geometry.estimate_homography(src[:4], dst[:4]), H_TRUE, atol=1e-6)


def test_normalisation_gives_zero_mean_and_root_two_spread():
    points = grid_points() * 7 + 1000
    t = geometry.normalising_transform(points)
    moved = geometry.apply_homography(t, points)
    np.testing.assert_allclose(moved.mean(axis=0), 0, atol=1e-9)
    assert np.sqrt((moved**2).sum(axis=1).mean()) == pytest.approx(np.sqrt(2))


def test_degenerate_samples_give_none_not_nan():
    line = np.column_stack([np.arange(6.0), 2 * np.arange(6.0)])
    assert geometry.estimate_homography(line[:4], line[:4] + 1) is None
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    assert geometry.estimate_homography(square, np.zeros((4, 2))) is None
    assert geometry.estimate_homography(square, square * np.nan) is None


def test_ransac_homography_with_half_outliers_and_noise():
    rng = np.random.default_rng(1)
    src = grid_points(200, seed=2)
    dst = geometry.apply_homography(H_TRUE, src) + rng.normal(0, 0.5, (200, 2))
    outliers = rng.random(200) < 0.5
    dst[outliers] = rng.uniform(0, 500, (outliers.sum(), 2))
    fit = geometry.homography_ransac(keypoints(src), keypoints(dst), identity_matches(200))
    assert geometry.corner_error(fit.homography, H_TRUE, width=512, height=512) < 1.0
    found = np.zeros(200, bool)
    found[fit.inliers.pairs[:, 0]] = True
    assert (found == ~outliers).mean() > 0.97
    assert fit.inlier_ratio == pytest.approx(found.mean())


def test_homography_ransac_bad_inputs():
    few = keypoints(grid_points(3))
    with pytest.raises(ValueError, match="need at least 4 matches to estimate a homography, got 3"):
        geometry.homography_ransac(few, few, identity_matches(3))
    collinear = keypoints(np.column_stack([np.arange(10.0), np.arange(10.0)]))
    with pytest.raises(ValueError, match="degenerate"):
        geometry.homography_ransac(collinear, collinear, identity_matches(10))
    with pytest.raises(gv.PortValueError, match="keypoint positions must be finite"):
        gv.KeypointsPort.validate(keypoints([[np.nan, 1.0]]))


def test_identical_points_give_the_identity():
    src = keypoints(grid_points(30))
    fit = geometry.homography_ransac(src, src, identity_matches(30))
    np.testing.assert_allclose(fit.homography, np.eye(3), atol=1e-9)


def test_ransac_iterations_formula():
    # N = log(1 - p) / log(1 - (1 - e)^s), rounded up
    assert fitting.ransac_iterations(0.5, 4, 0.99) == 72
    assert fitting.ransac_iterations(0.3, 2, 0.99) == 7
    assert fitting.ransac_iterations(0.0, 4, 0.99) == 1


def test_warp_by_a_translation_shifts_the_image():
    image = np.random.default_rng(0).random((40, 50)).astype(np.float32)
    shift = np.array([[1, 0, 3.0], [0, 1, 2.0], [0, 0, 1]])
    warped = geometry.warp(image, shift)
    np.testing.assert_allclose(warped.image[2:, 3:], image[:-2, :-3], atol=1e-6)
    assert not warped.valid[:2].any() and warped.valid[5:, 5:].all()
    with pytest.raises(ValueError, match="singular"):
        geometry.warp(image, np.zeros((3, 3)))


def test_random_warp_is_seeded_and_within_its_ranges():
    image = np.random.default_rng(0).random((64, 64)).astype(np.float32)
    a, b = synthetic.random_warp(image, seed=3), synthetic.random_warp(image, seed=3)
    np.testing.assert_array_equal(a.homography, b.homography)
    affine = a.homography[:2, :2]
    scale = np.sqrt(abs(np.linalg.det(affine)))
    assert 0.6 < scale < 1.4
    centre = np.array([[31.5, 31.5]])
    assert np.abs(geometry.apply_homography(a.homography, centre) - centre).max() < 1e-9


def test_two_views_and_stitching_with_the_true_homography():
    image = np.random.default_rng(0).random((60, 100, 3)).astype(np.float32)
    views = synthetic.two_views(image, overlap=0.5, seed=0)
    pano = geometry.stitch(views.left, views.right, views.homography)
    assert pano.shape[2] == 3 and pano.shape[1] >= 95
    rows, cols = views.right.shape[:2]
    corners = np.array([[0, 0], [cols - 1, 0], [cols - 1, rows - 1], [0, rows - 1]], float)
    mapped = geometry.apply_homography(views.homography, corners)
    top, left = (int(v) for v in np.floor(np.minimum(mapped.min(axis=0), 0))[::-1])
    # where only the left view contributes, the panorama is the left view
    np.testing.assert_allclose(
        pano[10 - top : 50 - top, 2 - left : 15 - left], views.left[10:50, 2:15], atol=1e-5
    )


def test_line_fits_on_known_lines():
    x = np.linspace(0, 10, 11)
    points = np.column_stack([x, 2 * x + 1])
    line = fitting.fit_line_lstsq(points)
    np.testing.assert_allclose(fitting.line_residuals(line, points), 0, atol=1e-9)
    vertical = np.column_stack([np.full(5, 3.0), np.arange(5.0)])
    np.testing.assert_allclose(np.abs(fitting.fit_line_total(vertical)), [1, 0, 3], atol=1e-12)
    with pytest.raises(ValueError, match="all points coincide"):
        fitting.fit_line_total(np.ones((4, 2)))
    with pytest.raises(ValueError, match="need at least 2 points"):
        fitting.fit_line_lstsq(np.ones((1, 2)))


def test_weighted_least_squares_ignores_zero_weight():
    x = np.linspace(0, 10, 11)
    points = np.column_stack([x, 0.5 * x])
    points[3, 1] = 100.0
    weights = np.ones(11)
    weights[3] = 0
    line = fitting.fit_line_weighted_node(points, weights)
    clean = np.delete(points, 3, axis=0)
    np.testing.assert_allclose(fitting.line_residuals(line, clean), 0, atol=1e-9)


def test_ransac_line_beats_least_squares_with_outliers():
    sample = synthetic.line_points(count=200, outlier_ratio=0.4, seed=0)
    robust = fitting.fit_line_ransac(sample.points, threshold=3.0)
    assert fitting.line_distance(robust.line, sample.truth) < 0.5
    assert fitting.line_distance(fitting.fit_line_lstsq(sample.points), sample.truth) > 2.0
    assert robust.inliers.sum() == pytest.approx(120, abs=10)


def test_gauss_newton_refinement_lowers_the_error():
    sample = synthetic.line_points(count=100, outlier_ratio=0.0, noise=1.0, seed=1)
    rough = sample.truth + np.array([0.02, -0.02, 1.0])
    rough /= np.hypot(*rough[:2])
    refined = fitting.refine_line(rough, sample.points)
    cost = lambda line: (fitting.line_residuals(line, sample.points) ** 2).sum()  # noqa: E731
    assert cost(refined) < cost(rough)
    np.testing.assert_allclose(
        refined,
        fitting.fit_line_total(sample.points)
        * np.sign(refined[0] * fitting.fit_line_total(sample.points)[0]),
        atol=1e-6,
    )


def test_ransac_keeps_the_refit_even_with_one_inlier_fewer():
    """The case the old rule got wrong: a sample-line through two noisy points crosses one
    outlier more than the least-squares line does. The refit must win: its error against
    the true line is far smaller, though it has one inlier fewer."""
    rng = np.random.default_rng(3)
    x = np.linspace(0, 100, 101)
    points = np.column_stack([x, 0.5 * x + 2 + rng.normal(0, 0.1, x.size)])
    points = np.vstack([points, [[50.0, 0.5 * 50 + 2 + 1.25]]])  # 1.25 above the true line
    truth = np.array([-0.5, 1.0, -2.0]) / np.hypot(0.5, 1.0)  # a x + b y + c = 0, (a, b) unit

    tilted = truth - [0.0, 0.0, 0.5]  # parallel, 0.5 px towards the outlier

    def distances(line):
        return np.abs(points @ line[:2] + line[2])

    def total_least_squares(index):
        chosen = points[index]
        centre = chosen.mean(axis=0)
        normal = np.linalg.svd(chosen - centre)[2][-1]
        return np.array([*normal, -normal @ centre])

    found = fitting.ransac(
        len(points), 2, lambda sample: tilted, distances, 1.0, refit=total_least_squares
    )
    assert distances(tilted).__lt__(1.0).sum() == 102  # the sample model crosses the outlier
    assert found.inliers.sum() == 101 and not found.inliers[-1]
    error = np.abs(np.array([[0.0, 2.0], [100.0, 52.0]]) @ found.model[:2] + found.model[2])
    assert error.max() < 0.1  # within 0.1 px of the true line at both ends (the sample: 0.5)
    assert np.allclose(np.sign(found.model[1]) * found.model, np.sign(truth[1]) * truth, atol=0.01)
