"""Segments drawn in one compiled pass give the pixels skimage.draw.line gives each."""

from __future__ import annotations

import numpy as np
import pytest
from skimage.draw import line

from graphvision_plugins.shared.draw import draw_segment, draw_segments


def test_many_segments_equal_skimage_line_clipped_and_in_order():
    rng = np.random.default_rng(3)
    starts = rng.uniform(-20, 80, (400, 2))
    ends = rng.uniform(-20, 80, (400, 2))
    ends[:40] = starts[:40]  # single points
    ends[40:80, 0] = starts[40:80, 0]  # vertical
    ends[80:120, 1] = starts[80:120, 1]  # horizontal
    colours = rng.random((400, 3)).astype(np.float32)
    expected = np.zeros((60, 70, 3), np.float32)
    for p, q, colour in zip(starts, ends, colours, strict=True):  # skimage's pixels, clipped
        rr, cc = line(int(round(p[1])), int(round(p[0])), int(round(q[1])), int(round(q[0])))
        inside = (rr >= 0) & (rr < 60) & (cc >= 0) & (cc < 70)
        expected[rr[inside], cc[inside]] = colour
    drawn = np.zeros_like(expected)
    draw_segments(drawn, starts, ends, colours)
    np.testing.assert_array_equal(drawn, expected)
    one = np.zeros_like(expected)
    for p, q, colour in zip(starts, ends, colours, strict=True):
        draw_segment(one, p, q, colour)
    np.testing.assert_array_equal(drawn, one)


def test_half_pixel_ends_round_half_to_even_as_round_does():
    drawn, expected = np.zeros((8, 8, 3), np.float32), np.zeros((8, 8, 3), np.float32)
    starts, ends = np.array([[0.5, 2.5], [1.5, 0.5]]), np.array([[6.5, 3.5], [1.5, 7.5]])
    draw_segments(drawn, starts, ends, np.ones((2, 3)))
    for p, q in zip(starts, ends, strict=True):
        draw_segment(expected, p, q, (1.0, 1.0, 1.0))
    np.testing.assert_array_equal(drawn, expected)


def test_a_point_that_is_not_finite_is_refused():
    with pytest.raises(ValueError, match="a segment's end point is not finite"):
        draw_segments(np.zeros((4, 4, 3)), np.array([[0.0, np.nan]]), np.zeros((1, 2)), [1, 1, 1])
