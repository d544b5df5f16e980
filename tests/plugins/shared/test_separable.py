"""The compiled separable core equals scipy.ndimage for every boundary, order and shape."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi

from graphvision_plugins.shared.separable import (
    correlate_separable,
    gaussian_derivative,
    gaussian_taps,
    smooth_gaussian,
)

RNG = np.random.default_rng(11)


@pytest.mark.parametrize("mode", ["reflect", "mirror", "nearest", "wrap", "constant"])
@pytest.mark.parametrize("shape", [(37, 53), (20, 31, 3), (5, 200)])
@pytest.mark.parametrize("sigma", [0.7, 2.0, 5.0])
def test_gaussian_equals_scipy_within_1e6(mode, shape, sigma):
    image = RNG.random(shape, dtype=np.float32)
    sigmas = (sigma, sigma, 0) if len(shape) == 3 else sigma
    expected = ndi.gaussian_filter(image, sigmas, mode=mode, truncate=3.0)
    np.testing.assert_allclose(smooth_gaussian(image, sigma, mode, 3.0), expected, atol=1e-6)


@pytest.mark.parametrize("order", [(0, 1), (1, 0)])
def test_derivative_of_gaussian_equals_scipy(order):
    image = RNG.random((48, 40), dtype=np.float32)
    expected = ndi.gaussian_filter(image, 1.5, order=order, truncate=3.0)
    taps = [gaussian_taps(1.5, 3.0, o) for o in order]
    np.testing.assert_allclose(correlate_separable(image, *taps), expected, atol=1e-6)


def test_unequal_row_and_column_taps_match_two_correlate1d_calls():
    image = RNG.random((30, 30), dtype=np.float32)
    column, row = np.array([1.0, 2.0, 1.0]) / 4, np.array([-1.0, 0.0, 1.0, 0.5, 0.25])
    expected = ndi.correlate1d(
        ndi.correlate1d(image, column, axis=0, mode="nearest"), row, axis=1, mode="nearest"
    )
    np.testing.assert_allclose(
        correlate_separable(image, column, row, "nearest"), expected, atol=1e-6
    )


@pytest.mark.parametrize("order", [(0, 2), (2, 0), (1, 1), (2, 1)])
@pytest.mark.parametrize("mode", ["reflect", "nearest", "constant"])
def test_float64_derivatives_equal_scipy_within_1e12(order, mode):
    """float64 images stay float64: callers that keep the precision lose nothing."""
    image = RNG.random((33, 47))
    # reference: scipy.ndimage.gaussian_filter(image, 1.3, order=order, mode=mode)
    expected = ndi.gaussian_filter(image, 1.3, order=order, mode=mode)
    out = gaussian_derivative(image, 1.3, order, mode)
    assert out.dtype == np.float64
    np.testing.assert_allclose(out, expected, atol=1e-12)


def test_only_orders_0_1_and_2():
    with pytest.raises(ValueError, match="order must be 0, 1 or 2"):
        gaussian_taps(1.0, order=3)


@pytest.mark.parametrize("mode", ["reflect", "mirror", "nearest", "wrap", "constant"])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_derivative_of_a_constant_is_exactly_zero(mode, dtype):
    """Antisymmetric taps are applied as h(u)·[f(i + u) − f(i − u)], as scipy does."""
    flat = np.full((17, 23), 0.3, dtype)
    slope, smooth = gaussian_taps(1.7, 3.0, order=1), gaussian_taps(1.7, 3.0)
    interior = (slice(6, -6), slice(6, -6))  # a zero boundary is not constant
    for taps in [(smooth, slope), (slope, smooth)]:
        assert not np.any(correlate_separable(flat, *taps, mode)[interior])


def test_unsymmetric_symmetric_and_antisymmetric_taps_take_their_own_path():
    image = RNG.random((25, 29), dtype=np.float32)
    for taps in [np.array([0.2, 0.5, 0.3]), np.array([0.25, 0.5, 0.25]), np.array([-1.0, 0, 1.0])]:
        # reference: two scipy.ndimage.correlate1d calls, mode "reflect"
        expected = ndi.correlate1d(ndi.correlate1d(image, taps, axis=0), taps, axis=1)
        np.testing.assert_allclose(correlate_separable(image, taps, taps), expected, atol=1e-6)


@pytest.mark.parametrize("mode", ["reflect", "constant"])
def test_a_float32_image_into_a_float64_out_equals_its_float64_copy_to_the_bit(mode):
    """One compiled core for both: the passes compute in the output's dtype, each float32
    sample widened where it is read (was a copy of the core, ``correlate_both_wide``)."""
    from graphvision_plugins.shared.separable import _boundary_index
    from graphvision_plugins.shared.separable_kernels import correlate_both

    image = RNG.random((19, 26), dtype=np.float32)
    image.flat[0] = np.float32(1e-40)  # a subnormal widens exactly too
    smooth = gaussian_taps(1.3)
    for column, symmetry in [(smooth, 1), (gaussian_taps(1.3, order=1), -1), (RNG.random(9), 0)]:
        rows = _boundary_index(19, column.size // 2, mode)
        columns = _boundary_index(26, smooth.size // 2, mode)
        wide, expected = np.empty((19, 26)), np.empty((19, 26))
        arguments = (column, symmetry, rows, smooth, 1, columns)
        correlate_both(image, *arguments, wide)
        correlate_both(image.astype(np.float64), *arguments, expected)
        np.testing.assert_array_equal(wide, expected)
        assert not np.array_equal(wide.astype(np.float32), wide)  # float64 sums, not float32
