"""The compiled RGB → HSV / L*a*b* / YCbCr conversions equal, to the bit, the array formulas
they replaced (kept here as the reference, as they were in ``colour/_spaces.py``)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import skimage.data

from graphvision_plugins import colour
from graphvision_plugins.colour._spaces import (
    D65_WHITE,
    LAB_EPSILON,
    LAB_SLOPE,
    XYZ_FROM_RGB,
    YCBCR_FROM_RGB,
    YCBCR_OFFSET,
)


def _linear(image: np.ndarray, matrix: np.ndarray, offset: np.ndarray) -> np.ndarray:
    out = np.empty_like(image)
    for row in range(3):
        plane = out[..., row]
        plane[...] = offset[row]
        for col in range(3):
            plane += image.dtype.type(matrix[row, col]) * image[..., col]
    return out


def _hsv(rgb: np.ndarray) -> np.ndarray:
    value = rgb.max(axis=-1)
    chroma = value - rgb.min(axis=-1)
    safe_chroma = np.where(chroma > 0, chroma, 1.0)
    saturation = np.where(value > 0, chroma / np.where(value > 0, value, 1.0), 0.0)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    hue = np.where(
        value == r,
        ((g - b) / safe_chroma) % 6.0,
        np.where(value == g, (b - r) / safe_chroma + 2.0, (r - g) / safe_chroma + 4.0),
    )
    hue = np.where(chroma > 0, hue / 6.0, 0.0)
    return np.stack([hue, saturation, value], axis=-1)


def _srgb_linear(channels: np.ndarray) -> np.ndarray:
    """sRGB linearised in float64 with the C library's ``pow`` (``math.pow``), as the kernels
    call it and as their table of the 8-bit levels holds it."""
    rgb = channels.astype(np.float64)
    linear = rgb / 12.92
    curved = rgb > 0.04045
    base = (rgb[curved] + 0.055) / 1.055
    linear[curved] = [math.pow(value, 2.4) for value in base]
    return linear


def _lab(channels: np.ndarray) -> np.ndarray:
    linear = _srgb_linear(channels)
    xyz = _linear(linear, XYZ_FROM_RGB / D65_WHITE[:, None], np.zeros(3))
    f = LAB_SLOPE * xyz + 16.0 / 116.0
    above = xyz > LAB_EPSILON
    f[above] = [math.cbrt(value) for value in xyz[above]]  # the C library's, as numba's
    lab = np.empty_like(f)
    lab[..., 0] = 116.0 * f[..., 1] - 16.0
    lab[..., 1] = 500.0 * (f[..., 0] - f[..., 1])
    lab[..., 2] = 200.0 * (f[..., 1] - f[..., 2])
    return lab


def _reference(rgb: np.ndarray, space: str) -> np.ndarray:
    if space == "ycbcr" and rgb.dtype == np.float32:
        return _linear(rgb, YCBCR_FROM_RGB, YCBCR_OFFSET).astype(np.float32)
    if space == "lab":
        return _lab(rgb)  # the levels are those of the input's float
    rgb = np.asarray(rgb, dtype=np.float64)
    if space == "ycbcr":
        return _linear(rgb, YCBCR_FROM_RGB, YCBCR_OFFSET)
    return _hsv(rgb)


def _inputs() -> list[np.ndarray]:
    rng = np.random.default_rng(7)
    levels = np.arange(256) / 255.0  # every 8-bit level in each channel, ties between channels
    grid = np.stack(np.meshgrid(levels[::15], levels[::15], levels[::15]), axis=-1)
    astronaut = skimage.data.astronaut()[::3, ::3] / 255.0
    return [
        astronaut,
        astronaut.astype(np.float32),
        rng.random((33, 47, 3)),
        rng.random((20, 30, 3)).astype(np.float32),
        grid.reshape(-1, 18, 3),
        np.zeros((2, 2, 3)),
    ]


@pytest.mark.parametrize("space", colour.SPACES)
def test_compiled_conversion_equals_the_array_formulas(space):
    for rgb in _inputs():
        expected = _reference(rgb, space)
        found = colour.rgb_to(rgb, space)
        assert found.dtype == expected.dtype
        np.testing.assert_array_equal(found, expected)
        single = rgb.astype(np.float32)
        node = colour.from_rgb(single, space=space)
        reference = _reference(single, space).astype(np.float32)
        if space != "hsv":
            np.testing.assert_array_equal(node, reference)
            continue
        # HSV of float32 is computed in float32 (rgb_to_hsv_single): value is the same;
        # hue and saturation, in [0, 1], take three float32 roundings instead of one at the
        # end: each at most half an ulp of a value below 8, the hue's divided by 6, so they
        # stay within 2⁻²³ of the float64 result rounded (2⁻²⁴ seen)
        np.testing.assert_array_equal(node[..., 2], reference[..., 2])
        np.testing.assert_allclose(node, reference, rtol=0, atol=2**-23)


def test_rgb_to_refuses_an_image_without_three_channels():
    with pytest.raises(ValueError, match="3 channels in its last axis"):
        colour.rgb_to(np.zeros((4, 4)), "hsv")
