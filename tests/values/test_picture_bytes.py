"""A picture's PNG bytes: its values rounded as round(clip(x, 0, 1) × 255) in float64, NaN
drawn 0 (the formula written out here with numpy is the reference)."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from graphvision.values.pictures import png_bytes


def _reference(picture: np.ndarray) -> np.ndarray:
    values = np.nan_to_num(picture.astype(np.float64), nan=0.0, posinf=1.0, neginf=0.0)
    return np.round(np.clip(values, 0.0, 1.0) * 255.0).astype(np.uint8)


@pytest.mark.parametrize(
    "picture",
    [
        np.random.default_rng(3).random((70, 90, 3), dtype=np.float32),
        np.random.default_rng(4).normal(0.5, 1.0, (80, 66)),  # out of range both ways
        ((np.arange(256 * 64) % 256 + 0.5) / 255).astype(np.float32).reshape(64, 256),  # halves
        np.array([[np.nan, np.inf, -np.inf, 0.5 / 255] * 16] * 64),
    ],
)
def test_png_pixels_are_the_rounded_clipped_values(picture):
    decoded = np.asarray(Image.open(io.BytesIO(png_bytes(picture))))
    assert np.array_equal(decoded, _reference(picture))
