"""The Gaussian pyramid computes only the pixels a halving keeps: the same values, to the
bit, as blurring the whole level and keeping every second row and column (the old path)."""

from __future__ import annotations

import numpy as np
import pytest
import skimage.data

from graphvision_plugins import pyramids
from graphvision_plugins.pyramids import blur


def _old_levels(image: np.ndarray, levels: int, sigma: float) -> list[np.ndarray]:
    result = [image.astype(np.float32)]
    for _ in range(levels - 1):
        if min(result[-1].shape[:2]) < 2:
            break
        result.append(np.ascontiguousarray(blur(result[-1], sigma)[::2, ::2]))
    return result


@pytest.mark.parametrize("sigma", [0.5, 1.0, 1.6, 3.0])
def test_halved_blur_equals_blur_then_subsample(sigma):
    rng = np.random.default_rng(11)
    images = [
        (skimage.data.camera()[::3, ::3] / 255.0).astype(np.float32),
        rng.random((37, 21)).astype(np.float32),  # odd sizes: the last row and column kept
        (skimage.data.astronaut()[::7, ::7] / 255.0).astype(np.float32),
        rng.random((3, 2)).astype(np.float32),  # smaller than the kernel: mirrored taps
    ]
    for image in images:
        expected = _old_levels(image, 5, sigma)
        found = pyramids.gaussian_levels(image, 5, sigma)
        assert len(found) == len(expected)
        for got, want in zip(found, expected, strict=True):
            assert got.shape == want.shape
            np.testing.assert_array_equal(got, want)


def test_level_zero_is_the_image_read_only_not_a_copy():
    image = np.random.default_rng(2).random((9, 12)).astype(np.float32)
    first = pyramids.gaussian_pyramid(image, levels=3).levels[0]
    assert np.shares_memory(first, image)
    with pytest.raises(ValueError, match="read-only"):
        first[0, 0] = 0.5
    assert image.flags.writeable  # the caller's array is left as it was
