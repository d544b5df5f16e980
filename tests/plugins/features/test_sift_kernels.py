"""The compiled SIFT kernels against the vectorised numpy code they replaced and against scipy.

``data/sift_astronaut_crop_e81c6dd.npz`` is the output of the previous, vectorised
implementation (commit e81c6dd, numpy extrema filters, batched solves, whole-image
gradients, ``bincount`` orientation histograms), recorded with::

    image = (skimage.data.astronaut().mean(axis=2) / 255).astype(np.float32)
    found = features.sift(np.ascontiguousarray(image[60:188, 170:298]))
    np.savez_compressed(path, xy=found.keypoints.xy, scale=found.keypoints.scale,
                        orientation=found.keypoints.orientation,
                        response=found.keypoints.response, descriptors=found.descriptors)
"""

from __future__ import annotations

import math
from pathlib import Path

import numba
import numpy as np
import pytest
import scipy.ndimage as ndi
import skimage.data

from graphvision_plugins import features
from graphvision_plugins.features import _dog_pyramid, _sift_descriptors
from graphvision_plugins.features._dog_kernels import _solve3, upsample_twice

RECORDED = Path(__file__).parent / "data" / "sift_astronaut_crop_e81c6dd.npz"


@pytest.fixture(scope="module")
def crop():
    image = (skimage.data.astronaut().mean(axis=2) / 255).astype(np.float32)
    return np.ascontiguousarray(image[60:188, 170:298])


def test_sift_equals_the_vectorised_implementation_it_replaced(crop):
    before = np.load(RECORDED)
    found = features.sift(crop)
    assert len(found.keypoints) == len(before["xy"]) == 101
    np.testing.assert_allclose(found.keypoints.xy, before["xy"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(found.keypoints.scale, before["scale"], rtol=1e-12)
    np.testing.assert_allclose(found.keypoints.orientation, before["orientation"], atol=1e-9)
    np.testing.assert_allclose(found.keypoints.response, before["response"], rtol=1e-9)
    # float32 descriptors: the solve's last bits may move a value by an ulp, no more
    np.testing.assert_allclose(found.descriptors, before["descriptors"], rtol=0, atol=1e-6)


def test_doubling_equals_scipy_zoom():
    image = np.random.default_rng(3).random((37, 52)).astype(np.float32)
    expected = ndi.zoom(image, 2, order=1, grid_mode=True, mode="nearest")
    np.testing.assert_array_equal(upsample_twice(image), expected)


@numba.njit(cache=False)
def _libm_atan2(dy, dx):  # pragma: no cover - compiled
    """float32 ``atan2`` of the C library, element by element: numpy's own AVX-512
    ``arctan2`` differs from it in the last bit for some values on machines that have it."""
    out = np.empty_like(dy)
    for i in range(dy.size):
        out.flat[i] = math.atan2(dy.flat[i], dx.flat[i])
    return out


def test_gradients_are_computed_where_windows_reach_and_equal_whole_image_ones(crop):
    keypoints, pyramid, where = _dog_pyramid.detect_dog(crop)
    keypoints, where = _sift_descriptors.assign_orientations(pyramid, where, keypoints)
    _sift_descriptors.sift_descriptors(pyramid, where, keypoints.orientation)
    assert pyramid.gradients, "no level was described"
    for (octave, layer), (magnitude, angle, done) in pyramid.gradients.items():
        level = pyramid.gaussians[octave][layer]
        dx, dy = np.zeros_like(level), np.zeros_like(level)
        dx[:, 1:-1] = level[:, 2:] - level[:, :-2]
        dy[1:-1, :] = level[2:, :] - level[:-2, :]
        np.testing.assert_array_equal(magnitude[done], np.hypot(dx, dy)[done])
        np.testing.assert_array_equal(angle[done], _libm_atan2(dy, dx)[done])
        assert not done[0].any() and not done[:, -1].any()  # border pixels are never sampled
    first = [done for (octave, _), (_, _, done) in pyramid.gradients.items() if octave == 0]
    assert np.mean([d.mean() for d in first]) < 0.9  # not the whole doubled image


@pytest.mark.parametrize("seed", range(3))
def test_three_by_three_solve_agrees_with_lapack(seed):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(3, 3))
    a[0, 0] = 1e-9 if seed == 0 else a[0, 0]  # a tiny first pivot forces a row exchange
    b = rng.normal(size=3)
    x = np.empty(3)
    det = _solve3(a.copy(), b.copy(), x)
    np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-10)
    assert det == pytest.approx(np.linalg.det(a), rel=1e-10)


def test_the_octave_stack_is_blurred_in_place_as_smooth_gaussian_blurs_it():
    from graphvision_plugins.shared.separable import smooth_gaussian

    stack = np.random.default_rng(0).random((6, 37, 51)).astype(np.float32)
    steps = [1.2, 1.5, 1.9, 2.4, 3.1]
    expected = stack.copy()
    for i, step in enumerate(steps, start=1):
        expected[i] = smooth_gaussian(expected[i - 1], step, truncate=3.0)
    _dog_pyramid._blur_stack(stack, steps)
    np.testing.assert_array_equal(stack, expected)
