"""Normalised cross-correlation's compiled denominator gives the same map, to the bit, as
the array formulas it replaced (kept here as the reference)."""

from __future__ import annotations

import numpy as np
import skimage.data
from scipy.signal import fftconvolve

from graphvision_plugins.pyramids import correlation_map


def _window_sums(image: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    h, w = shape
    integral = np.zeros((image.shape[0] + 1, image.shape[1] + 1))
    integral[1:, 1:] = image.cumsum(axis=0).cumsum(axis=1)
    return integral[h:, w:] - integral[:-h, w:] - integral[h:, :-w] + integral[:-h, :-w]


def _reference(image: np.ndarray, template: np.ndarray) -> np.ndarray:
    data = image.astype(np.float64)
    kernel = template.astype(np.float64)
    kernel = kernel - kernel.mean()
    response = fftconvolve(data, kernel[::-1, ::-1], mode="valid")
    count = kernel.size
    sums = _window_sums(data, kernel.shape)
    spread = np.maximum(_window_sums(data * data, kernel.shape) - sums * sums / count, 0.0)
    denominator = np.sqrt(spread * np.sum(kernel * kernel))
    tiny = np.finfo(np.float32).eps
    return np.where(denominator > tiny, response / np.maximum(denominator, tiny), 0.0)


def test_compiled_ncc_equals_the_array_formulas():
    rng = np.random.default_rng(5)
    camera = (skimage.data.camera()[::2, ::2] / 255.0).astype(np.float32)
    flat = np.zeros((40, 50), np.float32)
    flat[10:20, 10:30] = 0.5  # flat windows: the zero-denominator branch
    cases = [
        (camera, camera[100:120, 60:95].copy()),
        (rng.random((31, 44)).astype(np.float32), rng.random((7, 1)).astype(np.float32)),
        (flat, flat[8:16, 8:20].copy()),
        (camera[:9, :12].copy(), camera[:9, :12].copy()),  # one placement
    ]
    for image, template in cases:
        np.testing.assert_array_equal(
            correlation_map(image, template, "ncc"), _reference(image, template)
        )
