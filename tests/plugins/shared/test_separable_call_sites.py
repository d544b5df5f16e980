"""Every family that smooths or differentiates through the compiled core gets scipy's result.

Each case is the ``scipy.ndimage`` call a family made before it moved to
:mod:`graphvision_plugins.shared.separable`, written beside the call that replaced
it: float32 images agree within 1e-6, float64 ones (accumulators, the
Hessian, the LoG, board corners) within 1e-12.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi

from graphvision_plugins import edges, pyramids
from graphvision_plugins.edges import derivative_taps
from graphvision_plugins.shared.separable import gaussian_derivative, smooth_gaussian

RNG = np.random.default_rng(5)
IMAGE = RNG.random((41, 57), dtype=np.float32)


@pytest.mark.parametrize("kind", ["forward", "central", "sobel", "prewitt", "gaussian"])
@pytest.mark.parametrize(
    ("boundary", "mode"),
    [("mirror", "reflect"), ("replicate", "nearest"), ("wrap", "grid-wrap"), ("zero", "constant")],
)
def test_edges_derivatives_equal_two_correlate1d_calls(kind, boundary, mode):
    d, s = derivative_taps(kind, 1.4)
    # before: ndi.correlate1d across with the smoothing taps, then along with the derivative
    dx = ndi.correlate1d(ndi.correlate1d(IMAGE, s, axis=0, mode=mode), d, axis=1, mode=mode)
    dy = ndi.correlate1d(ndi.correlate1d(IMAGE, s, axis=1, mode=mode), d, axis=0, mode=mode)
    ours_x, ours_y = edges.gradient_images(IMAGE, kind, 1.4, boundary)
    np.testing.assert_allclose(ours_x, dx, atol=1e-6)
    np.testing.assert_allclose(ours_y, dy, atol=1e-6)
    node = edges.derivative(IMAGE, axis="y", kind=kind, sigma=1.4, boundary=boundary)
    np.testing.assert_allclose(node, dy, atol=1e-6)
    assert ours_x.dtype == ours_y.dtype == np.float32


@pytest.mark.parametrize("shape", [(41, 57), (30, 22, 3)])
def test_pyramid_blur_equals_gaussian_filter(shape):
    image = RNG.random(shape, dtype=np.float32)
    sigmas = (1.0, 1.0, 0.0) if len(shape) == 3 else 1.0
    # before: ndi.gaussian_filter(image, sigmas, mode="mirror", truncate=3.0, output=np.float32)
    expected = ndi.gaussian_filter(image, sigmas, mode="mirror", truncate=3.0, output=np.float32)
    np.testing.assert_allclose(pyramids.blur(image, 1.0), expected, atol=1e-6)


@pytest.mark.parametrize("mode", ["constant", "nearest", "reflect"])
def test_float64_smoothing_of_votes_and_boards_equals_gaussian_filter(mode):
    """Hough votes (constant, nearest), board rendering (nearest), corners (reflect)."""
    votes = RNG.poisson(3.0, (45, 38)).astype(np.float64)
    # before: ndi.gaussian_filter(votes, 1.5, mode=mode)
    expected = ndi.gaussian_filter(votes, 1.5, mode=mode)
    out = smooth_gaussian(votes, 1.5, mode)
    assert out.dtype == np.float64
    np.testing.assert_allclose(out, expected, atol=1e-12)


def test_log_as_two_second_derivatives_equals_gaussian_laplace():
    data = IMAGE.astype(np.float64)
    # before: ndi.gaussian_laplace(data, 2.5)
    expected = ndi.gaussian_laplace(data, 2.5)
    ours = gaussian_derivative(data, 2.5, (2, 0)) + gaussian_derivative(data, 2.5, (0, 2))
    np.testing.assert_allclose(ours, expected, atol=1e-12)
