"""stereo.coloured_points: the cloud of stereo.depth_points with each point's pixel colour."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins import camera, stereo


def _scene() -> tuple[np.ndarray, np.ndarray, object]:
    rng = np.random.default_rng(7)
    depth = rng.uniform(1.0, 5.0, (6, 8)).astype(np.float32)
    depth[2, 3] = depth[0, 0] = np.nan
    image = rng.uniform(0.0, 1.0, (6, 8, 3)).astype(np.float32)
    cam = camera.pinhole(fx=50.0, fy=40.0, cx=4.0, cy=3.0, width=8, height=6)
    return depth, image, cam


@pytest.mark.parametrize("step", [1, 2])
def test_each_point_carries_the_colour_of_the_pixel_it_came_from(step):
    depth, image, cam = _scene()
    points, colours = stereo.coloured_points(depth, cam, image, step=step)
    np.testing.assert_array_equal(points, stereo.depth_points(depth, cam, step=step))
    pixels = (cam.K @ points.T).T
    x, y = np.round(pixels[:, :2] / pixels[:, 2:]).astype(int).T  # back to the pixel
    np.testing.assert_array_equal(colours, image[y, x])
    assert colours.dtype == np.float32 and len(colours) == len(points)


def test_a_gray_image_gives_gray_colours():
    depth, image, cam = _scene()
    gray = image[:, :, 0]
    _, colours = stereo.coloured_points(depth, cam, gray)
    np.testing.assert_array_equal(colours[:, 0], colours[:, 2])
    np.testing.assert_array_equal(colours[:, 0], gray[np.isfinite(depth)])


def test_an_image_of_another_size_is_refused_by_name():
    depth, image, cam = _scene()
    with pytest.raises(ValueError, match=r"the image is 7×6 but the depth map is 8×6"):
        stereo.coloured_points(depth, cam, image[:, :7])


def test_point_colours_must_be_n_by_3_in_the_unit_range():
    port = stereo.PointColoursPort
    assert port.validate(np.zeros((0, 3), np.float32)).shape == (0, 3)
    with pytest.raises(gv.PortValueError, match=r"PointColours values in \[0, 1\]"):
        port.validate(np.full((2, 3), 2.0, np.float32))
    with pytest.raises(gv.PortValueError, match=r"float32 N×3 RGB"):
        port.validate(np.zeros((2, 4), np.float32))
