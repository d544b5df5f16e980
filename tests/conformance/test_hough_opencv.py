"""The OpenCV Hough implementations' own conventions: the score of a circle is the
share of its circumference on the edges, lines are kept ``min_distance`` bins apart."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("cv2", reason="the opencv backend needs opencv-python-headless (dev extra)")

from graphvision_plugins.opencv_backend import cv_hough_circles, cv_hough_lines

from .cases import _disks, _segments


def test_a_circle_scores_the_share_of_its_rim_on_the_edges() -> None:
    edges, image = _disks()
    whole = cv_hough_circles(edges, image, min_radius=8.0, max_radius=25.0).circles
    half = edges.copy()
    half[:, 70:] = False  # the dark disk at x = 100 loses its rim, the others keep theirs
    found = cv_hough_circles(half, image, min_radius=8.0, max_radius=25.0, threshold=0.01)
    assert whole[:, 3].min() > 0.9
    assert not np.any(np.hypot(*(found.circles[:, :2] - [100.0, 45.0]).T) < 3)


def test_lines_are_kept_apart_and_counted() -> None:
    edges = _segments()
    few = cv_hough_lines(edges, max_lines=2)
    assert few.count == 2 and few.lines.shape == (2, 3)
    lines = cv_hough_lines(edges).lines
    dtheta = np.abs(lines[:, None, 1] - lines[None, :, 1]) / (np.pi / 180)
    drho = np.abs(lines[:, None, 0] - lines[None, :, 0])
    apart = np.hypot(dtheta, drho) + np.eye(len(lines)) * 99
    assert apart.min() >= 5
    vertical = lines[(lines[:, 1] == 0) & (lines[:, 0] == 60)]  # the segment x = 60
    assert vertical[:, 2].tolist() == [edges[:, 60].sum()]  # one vote a point


def test_edges_and_image_of_different_sizes_are_refused() -> None:
    edges, image = _disks()
    with pytest.raises(ValueError, match="edges and image must have the same size"):
        cv_hough_circles(edges[:50], image, min_radius=8.0, max_radius=25.0)
    with pytest.raises(ValueError, match="edges and image must have the same size"):
        cv_hough_lines(edges[:50], image)
