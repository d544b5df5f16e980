"""The sliding-histogram median of an image of 8-bit levels gives the selection network's
values (the path every image took before), to the bit, and an image off the levels keeps
the network."""

from __future__ import annotations

import numpy as np
import pytest

from graphvision_plugins import filters
from graphvision_plugins.filters import _median
from graphvision_plugins.filters._median_histogram import LEVELS, level_codes
from graphvision_plugins.filters._median_kernels import median_by_network
from graphvision_plugins.filters._median_network import median_network, sort_network


def _network(image: np.ndarray, size: int, boundary: str) -> np.ndarray:
    half = size // 2
    rows = _median._boundary_index(image.shape[0], half, boundary)
    columns = _median._boundary_index(image.shape[1], half, boundary)
    out = np.empty((rows.size - 2 * half, columns.size - 2 * half), np.float32)
    selection, wire = median_network(size)
    median_by_network(image, rows, columns, sort_network(size), selection, wire, out, 512)
    return out


def _levels_image(shape: tuple[int, int], seed: int) -> np.ndarray:
    """8-bit levels as the engine reads them: noise over the full range (medians jump
    both ways), a smooth ramp, and a flat block (ties)."""
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 256, shape)
    codes[:, : shape[1] // 3] = np.arange(shape[1] // 3) * 7 % 256
    codes[: shape[0] // 2, shape[1] // 2 :] = 200
    return codes.astype(np.uint8).astype(np.float32) / np.float32(255.0)


def test_levels_are_an_8_bit_image_as_the_engine_reads_it():
    # graphvision.values.images reads uint8 as ``astype(float32) / float32(255)``
    read = np.arange(256, dtype=np.uint8).astype(np.float32) / np.float32(255.0)
    np.testing.assert_array_equal(LEVELS, read)
    codes = np.empty((1, 256), np.uint8)
    assert level_codes(read[None, :], LEVELS, codes)
    np.testing.assert_array_equal(codes[0], np.arange(256))


@pytest.mark.parametrize("boundary", ["mirror", "replicate", "wrap", "zero", "crop"])
@pytest.mark.parametrize("size", [7, 11])
@pytest.mark.parametrize("shape", [(40, 53), (15, 16), (9, 300)])
def test_histogram_median_equals_the_network(boundary, size, shape):
    if boundary == "crop" and min(shape) < size:
        pytest.skip("crop needs the window inside the image")
    image = _levels_image(shape, size + shape[1])
    np.testing.assert_array_equal(
        filters.median(image, size=size, boundary=boundary), _network(image, size, boundary)
    )


@pytest.mark.parametrize("boundary", ["mirror", "zero"])
def test_histogram_median_on_images_smaller_than_the_window(boundary):
    for shape in [(1, 9), (2, 2), (5, 1)]:
        image = _levels_image(shape, 3)
        np.testing.assert_array_equal(
            filters.median(image, size=7, boundary=boundary), _network(image, 7, boundary)
        )


def test_only_an_image_of_levels_takes_the_histogram():
    image = _levels_image((20, 30), 5)
    rows = _median._boundary_index(20, 3, "mirror")
    columns = _median._boundary_index(30, 3, "mirror")
    out = np.full((20, 30), -1.0, np.float32)
    assert _median._median_of_levels(image, rows, columns, out)
    np.testing.assert_array_equal(out, _network(image, 7, "mirror"))
    image[11, 17] = 0.3  # not k / 255 for any k
    out[:] = -1.0
    assert not _median._median_of_levels(image, rows, columns, out)
    assert np.all(out == -1.0)  # nothing written: the network fills it
    np.testing.assert_array_equal(filters.median(image, size=7), _network(image, 7, "mirror"))


def test_negative_zero_keeps_its_sign_bit_as_the_network_does():
    """−0.0 equals the level 0 but is not its bits: an image holding it keeps the network,
    whose medians keep the sign bit (the histogram's would be +0.0)."""
    image = np.full((20, 20), -0.0, np.float32)
    image[0, 0] = 1.0
    codes = np.empty(image.shape, np.uint8)
    assert not level_codes(image, LEVELS, codes)
    median = filters.median(image, size=7)
    np.testing.assert_array_equal(np.signbit(median), np.signbit(_network(image, 7, "mirror")))
    assert np.signbit(median).all()
