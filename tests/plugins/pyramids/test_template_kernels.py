"""Normalised cross-correlation: the compiled denominator gives the same map, to the bit, as
the array formulas it replaced (kept here as the reference), and the numerator by
circular real FFTs of the image's size matches ``fftconvolve``'s linear correlation to
float64 rounding."""

from __future__ import annotations

import numpy as np
import skimage.data
from scipy.signal import fftconvolve

from graphvision_plugins.pyramids import correlation_map
from graphvision_plugins.pyramids._template_kernels import normalise_response


def _window_sums(image: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    h, w = shape
    integral = np.zeros((image.shape[0] + 1, image.shape[1] + 1))
    integral[1:, 1:] = image.cumsum(axis=0).cumsum(axis=1)
    return integral[h:, w:] - integral[:-h, w:] - integral[h:, :-w] + integral[:-h, :-w]


def _numerator(image: np.ndarray, template: np.ndarray, centred: bool = True) -> np.ndarray:
    kernel = template.astype(np.float64)
    kernel = kernel - kernel.mean() if centred else kernel
    return fftconvolve(image.astype(np.float64), kernel[::-1, ::-1], mode="valid")


def _reference(image: np.ndarray, template: np.ndarray, response: np.ndarray) -> np.ndarray:
    data = image.astype(np.float64)
    kernel = template.astype(np.float64)
    kernel = kernel - kernel.mean()
    count = kernel.size
    sums = _window_sums(data, kernel.shape)
    spread = np.maximum(_window_sums(data * data, kernel.shape) - sums * sums / count, 0.0)
    denominator = np.sqrt(spread * np.sum(kernel * kernel))
    tiny = np.finfo(np.float32).eps
    return np.where(denominator > tiny, response / np.maximum(denominator, tiny), 0.0)


def _cases() -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(5)
    camera = (skimage.data.camera()[::2, ::2] / 255.0).astype(np.float32)
    flat = np.zeros((40, 50), np.float32)
    flat[10:20, 10:30] = 0.5  # flat windows: the zero-denominator branch
    return [
        (camera, camera[100:120, 60:95].copy()),
        (rng.random((31, 44)).astype(np.float32), rng.random((7, 1)).astype(np.float32)),
        (rng.random((37, 29)).astype(np.float32), rng.random((5, 8)).astype(np.float32)),
        (flat, flat[8:16, 8:20].copy()),
        (camera[:9, :12].copy(), camera[:9, :12].copy()),  # one placement
    ]


def test_compiled_ncc_denominator_equals_the_array_formulas():
    for image, template in _cases():
        kernel = template.astype(np.float64) - template.mean(dtype=np.float64)
        response = _numerator(image, template)
        compiled = normalise_response(
            image.astype(np.float64),
            response,
            *template.shape,
            float(np.sum(kernel * kernel)),
            float(np.finfo(np.float32).eps),
        )
        np.testing.assert_array_equal(compiled, _reference(image, template, response))


def test_fft_numerator_matches_linear_correlation_to_rounding():
    # the bound stated in docs/algorithms/colour-pyramids-frequency.md: 1e-12 of
    # sum|T| max|I| for the numerators, 1e-9 for the NCC map of these images
    for image, template in _cases():
        scale = np.abs(template).sum() * np.abs(image).max()
        for method, centred in (("correlation", False), ("zero_mean", True)):
            np.testing.assert_allclose(
                correlation_map(image, template, method),
                _numerator(image, template, centred),
                rtol=0,
                atol=1e-12 * scale,
            )
        ncc = correlation_map(image, template, "ncc")
        np.testing.assert_allclose(
            ncc, _reference(image, template, _numerator(image, template)), rtol=0, atol=1e-9
        )
