"""The compiled demosaicking equals, to the bit, the array formulas it replaced (kept here as
the reference, as they were in ``formation/_bayer.py``)."""

from __future__ import annotations

import numpy as np
import pytest
import skimage.data

from graphvision_plugins.formation import bayer_masks, demosaic, mosaic
from graphvision_plugins.formation._bayer import (
    _G_AT_RB,
    _RB_AT_BR,
    _RB_AT_G_COLUMN,
    _RB_AT_G_ROW,
)


def _convolve(image: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    half = kernel.shape[0] // 2
    padded = np.pad(image, half, mode="reflect")
    rows, cols = image.shape
    out = np.zeros_like(image)
    for dy, dx in zip(*np.nonzero(kernel), strict=True):
        out += kernel[dy, dx] * padded[dy : dy + rows, dx : dx + cols]
    return out


def _reference(raw: np.ndarray, pattern: str, method: str) -> np.ndarray:
    data = raw.astype(np.float32)
    red, green, blue = bayer_masks(raw.shape, pattern)
    if method == "bilinear":
        cross = np.array([[0, 1, 0], [1, 4, 1], [0, 1, 0]]) / 4.0
        box = np.array([[1, 2, 1], [2, 4, 2], [1, 2, 1]]) / 4.0
        out = np.stack(
            [
                _convolve(data * red, box),
                _convolve(data * green, cross),
                _convolve(data * blue, box),
            ],
            axis=-1,
        )
        return np.clip(out, 0, 1).astype(np.float32)
    green_at_rb = _convolve(data, _G_AT_RB)
    at_g_row = _convolve(data, _RB_AT_G_ROW)
    at_g_column = _convolve(data, _RB_AT_G_COLUMN)
    at_opposite = _convolve(data, _RB_AT_BR)
    rows_with_red = np.broadcast_to(red.any(axis=1, keepdims=True), raw.shape)
    out = np.empty((*raw.shape, 3))
    out[..., 1] = np.where(green, data, green_at_rb)
    for channel, own, other, own_rows in (
        (0, red, blue, rows_with_red),
        (2, blue, red, ~rows_with_red),
    ):
        at_green = np.where(own_rows, at_g_row, at_g_column)
        out[..., channel] = np.where(own, data, np.where(other, at_opposite, at_green))
    return np.clip(out, 0, 1).astype(np.float32)


@pytest.mark.parametrize("method", ["bilinear", "malvar"])
@pytest.mark.parametrize("pattern", ["RGGB", "BGGR", "GRBG", "GBRG"])
def test_compiled_demosaic_equals_the_array_formulas(pattern, method):
    rng = np.random.default_rng(3)
    scenes = [
        (skimage.data.astronaut()[::5, ::5] / 255.0).astype(np.float32),
        rng.random((23, 30, 3)).astype(np.float32),  # odd height: the tile cut at the border
        rng.random((5, 6, 3)).astype(np.float32),  # the smallest mosaic accepted
    ]
    for image in scenes:
        raw = mosaic(image, pattern=pattern)
        np.testing.assert_array_equal(
            demosaic(raw, pattern=pattern, method=method), _reference(raw, pattern, method)
        )


@pytest.mark.parametrize("method", ["bilinear", "malvar"])
def test_demosaic_of_values_below_the_normal_range_equals_the_array_formulas(method):
    # a product by a weight of 1/16 to 1/2 of a value near float32's smallest loses bits
    # in float32 (not in float64): such a mosaic is summed in float64 throughout
    rng = np.random.default_rng(5)
    raw = (rng.integers(1, 2**20, (12, 14)) * np.float32(2.0**-149)).astype(np.float32)
    raw[::3, ::2] = rng.random((4, 7)).astype(np.float32)  # normal values beside them
    np.testing.assert_array_equal(
        demosaic(raw, pattern="GBRG", method=method), _reference(raw, "GBRG", method)
    )


@pytest.mark.parametrize("method", ["bilinear", "malvar"])
def test_rows_near_values_below_the_normal_range_alone_are_summed_in_float64(method):
    # the float32-or-float64 choice is made per output row from the five rows it reads:
    # rows 0-9 below the normal range, rows 10-19 normal, each row exact either way
    rng = np.random.default_rng(6)
    raw = rng.random((20, 14)).astype(np.float32)
    raw[:10] = rng.integers(1, 2**20, (10, 14)) * np.float32(2.0**-149)
    for pattern in ("RGGB", "GRBG"):
        np.testing.assert_array_equal(
            demosaic(raw, pattern=pattern, method=method), _reference(raw, pattern, method)
        )


def test_a_value_below_the_normal_range_in_the_last_column_of_an_odd_width_is_seen():
    # the last sample of an odd-width row is not in a column pair of the row split. Red at
    # the green (4, 10) of GRBG: its first tap, 16·2⁻¹⁴⁹/16, gives 2⁻¹⁴⁹; its last,
    # 24·2⁻¹⁴⁹/16 = 1.5·2⁻¹⁴⁹, added in float64 gives 2.5·2⁻¹⁴⁹ → 2·2⁻¹⁴⁹ (ties to even),
    # but 1 + 2 = 3·2⁻¹⁴⁹ if the product were rounded to float32 first
    raw = np.zeros((9, 11), dtype=np.float32)
    raw[2, 10], raw[6, 10] = np.float32(16 * 2.0**-149), np.float32(24 * 2.0**-149)
    got = demosaic(raw, pattern="GRBG", method="malvar")
    np.testing.assert_array_equal(got, _reference(raw, "GRBG", "malvar"))
    assert got[4, 10, 0] == np.float32(2 * 2.0**-149)


def test_taps_of_other_weights_are_one_fma_only_where_the_magnitudes_span_few_binades():
    # R at the B pixel (5, 5) of RGGB: the sum so far is -3/16 · 2⁻⁷¹ (two rows up) and
    # 3/4 of the centre, 0.375 + 1.5 · 2⁻²⁵, lies on a float32 midpoint. Exactly, the sum
    # is just below it (rounds down); in float64 it rounds to the midpoint first, then
    # to even (up): the array formulas' value, which one float32 FMA would miss by one
    # step. Rows 0-2 and 8-11 read 2⁻⁷¹ or 0.5 alone (one binade), the FMA's, all equal.
    raw = np.zeros((12, 12), np.float32)
    raw[5, 5] = np.float32(0.5 + 2.0**-24)
    raw[3, 5] = np.float32(2.0**-71)
    raw[10, 1] = np.float32(0.5 + 2.0**-24)
    raw[1, 9] = np.float32(2.0**-71)
    found = demosaic(raw, pattern="RGGB", method="malvar")
    np.testing.assert_array_equal(found, _reference(raw, "RGGB", "malvar"))
    assert found[5, 5, 0] == np.float32(0.375 + 2.0**-24)  # rounded up, not 0.375 + 2⁻²⁵
