"""Hough lines and circles against drawn truths, a rotated checkerboard and the coins."""

from __future__ import annotations

import math

import numpy as np
import pytest
import skimage.data
import skimage.transform

import graphvision as gv
from graphvision_plugins import edges, hough

from ...conftest import PIPELINES

BOARD_LINES = 24.5 + 25.0 * np.arange(7)  # 25-px squares: boundaries between pixels 24 and 25, ...


def board_truth(angle: float) -> np.ndarray:
    """(ρ, θ) of the 14 interior lines of ``sample:checkerboard`` after
    ``skimage.transform.rotate(board, angle)`` (counter-clockwise on screen: θ decreases
    with y pointing down), about the centre (99.5, 99.5)."""
    centre = np.array([99.5, 99.5])
    truth = []
    for theta0 in (0.0, math.pi / 2):
        normal0 = np.array([math.cos(theta0), math.sin(theta0)])
        theta = theta0 - math.radians(angle)
        normal = np.array([math.cos(theta), math.sin(theta)])
        for rho0 in BOARD_LINES:
            rho = rho0 - normal0 @ centre + normal @ centre
            if theta < 0:
                truth.append((-rho, theta + math.pi))
            else:
                truth.append((rho, theta))
    return np.array(truth)


def _canonical(lines: np.ndarray) -> np.ndarray:
    """(ρ, θ) with θ in (−π/4, 3π/4]: (ρ, θ) and (−ρ, θ − π) are one line, and a line near
    θ = 0 may be found on either side of the wrap."""
    rho, theta = lines[:, 0], lines[:, 1]
    wrap = theta > 3 * math.pi / 4
    return np.column_stack([np.where(wrap, -rho, rho), np.where(wrap, theta - math.pi, theta)])


def match_lines(found: np.ndarray, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each true line, the ρ and θ errors of the nearest line found (each used once)."""
    found, truth = _canonical(found[:, :2]), _canonical(truth)
    cost = np.abs(found[:, None, 0] - truth[None, :, 0]) + 100 * np.abs(
        found[:, None, 1] - truth[None, :, 1]
    )
    nearest = cost.argmin(axis=0)
    assert len(set(nearest.tolist())) == len(truth)
    return np.abs(found[nearest, 0] - truth[:, 0]), np.abs(found[nearest, 1] - truth[:, 1])


@pytest.mark.parametrize("angle", [0.0, 20.0])
def test_checkerboard_interior_lines(angle):
    board = (skimage.data.checkerboard() / 255).astype(np.float32)
    image = skimage.transform.rotate(board, angle, order=1).astype(np.float32)
    found = edges.canny(image, sigma=1.0).edges
    result = hough.hough_lines(found, image)
    assert result.count == 14
    rho_error, theta_error = match_lines(result.lines, board_truth(angle))
    # unrotated, each step lies between two pixels and Canny marks one of them: 0.44 px
    # (0.0 when the tie kept both sides, before issue 24)
    assert rho_error.max() <= 0.5
    assert np.degrees(theta_error).max() <= 0.5


def test_hough_lines_pipeline_keeps_its_count_on_a_rotated_board():
    graph = gv.load_pipeline(PIPELINES / "hough_lines.yaml")
    assert gv.run(graph).outputs["count"] == 14
    board = (skimage.data.checkerboard() / 255).astype(np.float32)
    rotated = skimage.transform.rotate(board, 20, order=1).astype(np.float32)
    out = gv.run(graph, inputs={"image": rotated}).outputs
    assert out["count"] == 14
    assert out["drawing"].shape == (200, 200, 3)


def test_gradient_voting_rejects_clutter_that_plain_voting_accepts():
    rng = np.random.default_rng(0)
    image = np.full((120, 120), 0.2, np.float32)
    image[:, 60:] = 0.8  # one true line: x = 59.5 (θ = 0)
    image = np.clip(image + rng.normal(0, 0.03, image.shape), 0, 1).astype(np.float32)
    found = edges.canny(image, sigma=1.0, low=0.1, high=0.2).edges
    found |= rng.random(found.shape) < 0.05  # clutter: 5 % of the pixels, no gradient there
    # threshold: a line's covered length as a fraction of the longest's (issue 24): random
    # alignments of the clutter cover up to a fifth of the true line's 120 px
    plain = hough.hough_lines(found, threshold=0.15)
    informed = hough.hough_lines(found, image, threshold=0.15)
    assert informed.count == 1
    rho, theta = informed.lines[0, :2]
    if theta > math.pi / 2:  # θ = π − ε, ρ < 0 is the same line as θ = −ε, ρ > 0
        rho, theta = -rho, theta - math.pi
    assert abs(rho - 59.5) <= 0.5 and abs(theta) < math.radians(1)
    assert plain.count > 5  # random points align into spurious peaks without the gradient


def drawn_circles(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Three discs of known centres and radii on a noisy background."""
    truth = np.array([[40.0, 42.0, 18.0], [110.5, 50.0, 22.0], [75.0, 110.0, 15.5]])
    y, x = np.mgrid[0:150, 0:160].astype(np.float64)
    image = np.full(x.shape, 0.3)
    for cx, cy, r in truth:
        image[np.hypot(x - cx, y - cy) <= r] = 0.7
    image += np.random.default_rng(seed).normal(0, 0.04, image.shape)
    return np.clip(image, 0, 1).astype(np.float32), truth


@pytest.mark.parametrize("seed", range(2))
def test_circles_of_a_radius_range_are_found_with_their_radius(seed):
    image, truth = drawn_circles(seed)
    found = edges.canny(image, sigma=1.5, low=0.05, high=0.1).edges
    result = hough.hough_circles(found, image, min_radius=12, max_radius=26, sigma=1.5)
    assert result.count == 3
    order = np.argsort(result.circles[:, 0])
    circles = result.circles[order]
    expected = truth[np.argsort(truth[:, 0])]
    np.testing.assert_allclose(circles[:, :2], expected[:, :2], atol=1.0)
    np.testing.assert_allclose(circles[:, 2], expected[:, 2], atol=0.75)


def test_a_known_radius_finds_only_circles_of_that_radius():
    image, truth = drawn_circles(0)
    found = edges.canny(image, sigma=1.5, low=0.05, high=0.1).edges
    result = hough.hough_circles(found, image, min_radius=22, max_radius=22, threshold=0.25)
    assert result.count == 1
    np.testing.assert_allclose(result.circles[0, :2], truth[1, :2], atol=1.0)


def test_coins_are_found_with_the_radius_of_their_regions():
    out = gv.run(gv.load_pipeline(PIPELINES / "hough_circles.yaml")).outputs
    # reference: the 24 regions of pipelines/coins.yaml (threshold, morphology, labelling)
    regions = gv.run(gv.load_pipeline(PIPELINES / "coins.yaml")).outputs["regions"]
    centroids = np.column_stack([regions["centroid_x"], regions["centroid_y"]])
    equivalent_radius = np.sqrt(regions["area"] / math.pi)
    circles = out["circles"]
    assert out["count"] == 24
    gaps = np.linalg.norm(circles[:, None, :2] - centroids[None], axis=2)
    nearest = gaps.argmin(axis=1)
    assert len(set(nearest.tolist())) == 24  # one circle per coin, no false positive
    assert gaps.min(axis=1).max() < 4.0
    assert np.abs(circles[:, 2] - equivalent_radius[nearest]).mean() <= 0.8
    assert out["drawing"].shape == (303, 384, 3)


@pytest.mark.parametrize("value", [0.0, 0.6])
def test_a_constant_image_gives_no_lines_and_no_circles(value):
    flat = np.full((40, 50), value, np.float32)
    found = edges.canny(flat).edges
    lines = hough.hough_lines(found, flat)
    circles = hough.hough_circles(found, flat, min_radius=5, max_radius=10)
    assert lines.count == 0 and lines.lines.shape == (0, 3)
    assert circles.count == 0 and circles.circles.shape == (0, 4)
    assert hough.hough_lines(found).count == 0


def test_bad_parameters_are_refused_naming_them():
    image = np.zeros((20, 20), np.float32)
    mask = np.zeros((20, 20), bool)
    with pytest.raises(ValueError, match=r"min_radius \(9\) must be at most max_radius \(5\)"):
        hough.hough_circles(mask, image, min_radius=9, max_radius=5)
    with pytest.raises(ValueError, match=r"edges and image must have the same size"):
        hough.hough_lines(mask, image[:10])
    with pytest.raises(gv.ParameterError, match="theta_bins"):
        hough.hough_lines(mask, theta_bins=0)


def test_port_types_check_their_shape():
    with pytest.raises(gv.PortValueError, match=r"expected Lines \(float64 N×3"):
        hough.LinesPort.validate(np.zeros((2, 2)))
    with pytest.raises(gv.PortValueError, match=r"expected Circles \(float64 N×4"):
        hough.CirclesPort.validate(np.zeros((2, 3)))
    assert hough.CirclesPort.validate(np.zeros((0, 4))).shape == (0, 4)


def test_drawings_mark_what_was_found():
    image = np.zeros((30, 40), np.float32)
    drawn = hough.draw_lines(image, np.array([[10.0, 0.0, 1.0]]))  # the column x = 10
    np.testing.assert_allclose(drawn[:, 10], np.tile([0.95, 0.15, 0.1], (30, 1)), rtol=1e-6)
    assert drawn[:, 11].max() == 0
    circle = hough.draw_circles(image, np.array([[20.0, 15.0, 8.0, 1.0]]))
    np.testing.assert_allclose(circle[15, 28], [0.1, 0.95, 0.1], rtol=1e-6)
    np.testing.assert_allclose(circle[15, 20], [0.95, 0.15, 0.1], rtol=1e-6)


def test_lines_reusing_the_threads_votes_equal_a_fresh_accumulator_smoothed():
    """``hough.lines`` votes and smooths into arrays its thread keeps between calls: its
    accumulator equals ``line_accumulator`` (a new array) smoothed by the shared Gaussian,
    to the bit, and a result keeps its values after later calls, in this or another thread."""
    import threading

    from graphvision_plugins.hough._lines import line_accumulator
    from graphvision_plugins.shared.separable import smooth_gaussian

    rng = np.random.default_rng(5)
    masks = [rng.random((48, 64)) < 0.05 for _ in range(2)]
    first = hough.hough_lines(masks[0])
    kept = first.accumulator.copy()
    for mask in masks:
        votes = line_accumulator(mask, None, 180, 1.0, 5.0, False, 1.0)
        pad = 5 + 3 + 1  # min_distance + 3 vote_sigma + 1, the node's padding
        wrapped = np.concatenate([votes[-pad:, ::-1], votes, votes[:pad, ::-1]], axis=0)
        smoothed = smooth_gaussian(wrapped, 1.0, "nearest")[pad:-pad].astype(np.float32)
        np.testing.assert_array_equal(hough.hough_lines(mask).accumulator, smoothed)
    other: list = []
    worker = threading.Thread(target=lambda: other.append(hough.hough_lines(masks[1])))
    worker.start()
    worker.join(timeout=60)
    assert not worker.is_alive()
    np.testing.assert_array_equal(first.accumulator, kept)
    np.testing.assert_array_equal(other[0].lines, hough.hough_lines(masks[1]).lines)
