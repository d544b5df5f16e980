"""The compiled helpers of board corners equal the NumPy / SciPy calls they replace:
``np.gradient``, the saddle response and its peaks by ``maximum_filter``, bilinear samples
by ``map_coordinates(order=1)``, and the grid's homography by the normalised DLT."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from graphvision_plugins.camera._corner_kernels import (
    gradient,
    grid_homography,
    saddle_peaks,
    saddle_response,
    sample,
)
from graphvision_plugins.geometry import estimate_homography


def test_gradient_and_saddle_response_equal_numpy_to_the_bit():
    f = np.random.default_rng(0).random((37, 53))
    gy, gx = gradient(f)
    ny, nx = np.gradient(f)
    np.testing.assert_array_equal(gy, ny)
    np.testing.assert_array_equal(gx, nx)
    iyy, iyx = np.gradient(ny)
    ixy, ixx = np.gradient(nx)
    np.testing.assert_array_equal(saddle_response(f), -(ixx * iyy - ixy * iyx))


def test_saddle_peaks_equal_maximum_filter_away_from_the_border():
    rng = np.random.default_rng(1)
    response = np.round(rng.standard_normal((60, 70)) * 4) / 4  # ties count as peaks
    for radius in (2, 4):
        peaks = (response == ndimage.maximum_filter(response, 2 * radius + 1)) & (response > 0)
        border = radius + 1
        peaks[:border], peaks[-border:], peaks[:, :border], peaks[:, -border:] = (False,) * 4
        rows, cols = saddle_peaks(response, radius)
        np.testing.assert_array_equal(np.column_stack([rows, cols]), np.argwhere(peaks))


def test_sample_equals_map_coordinates_order_1():
    rng = np.random.default_rng(2)
    values = rng.random((20, 30))
    xs = np.concatenate([rng.uniform(-2, 31, 500), [0.0, 29.0, 29.0, -1e-9, 29.000001]])
    ys = np.concatenate([rng.uniform(-2, 21, 500), [0.0, 19.0, 0.5, 3.0, 5.0]])
    expected = ndimage.map_coordinates(values, [ys, xs], order=1)
    np.testing.assert_allclose(sample(values, xs, ys), expected, rtol=0, atol=1e-12)


def test_grid_homography_equals_the_normalised_dlt():
    j, i = np.mgrid[0:3, 0:7]
    src = np.column_stack([i.ravel(), j.ravel()]).astype(np.float64)
    h_true = np.array([[30.0, 2.0, 100.0], [-1.5, 28.0, 80.0], [1e-3, -2e-3, 1.0]])
    mapped = np.column_stack([src, np.ones(len(src))]) @ h_true.T
    dst = mapped[:, :2] / mapped[:, 2:]
    dst += np.random.default_rng(3).normal(0, 0.2, dst.shape)
    ok, h = grid_homography(src, dst)
    assert ok
    np.testing.assert_allclose(h, estimate_homography(src, dst), rtol=1e-8, atol=1e-10)
    assert not grid_homography(src[:7], dst[:7])[0]  # one row: collinear, degenerate
