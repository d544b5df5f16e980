"""The convolution theorem against spatial convolution; spectra and filters on sinusoids."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.ndimage as ndi

import graphvision as gv
from graphvision_plugins import filters, frequency


@pytest.mark.parametrize("boundary", filters.BOUNDARIES)
@pytest.mark.parametrize("kernel_shape", [(5, 8), (4, 3), (1, 1), (15, 15)])
def test_fft_convolution_equals_spatial_convolution(boundary, kernel_shape):
    rng = np.random.default_rng(sum(kernel_shape))
    image = rng.random((40, 53)).astype(np.float32)
    kernel = rng.normal(size=kernel_shape)
    # reference: filters.convolve (scipy.ndimage.correlate with the flipped kernel)
    expected = filters.convolve(image, kernel, boundary=boundary)
    found = frequency.fft_convolve(image, kernel, boundary=boundary)
    np.testing.assert_allclose(found, expected, atol=1e-5)


def test_fft_convolution_of_colour_images_goes_channel_by_channel():
    rng = np.random.default_rng(3)
    image = rng.random((20, 24, 3)).astype(np.float32)
    kernel = rng.normal(size=(3, 5))
    expected = filters.convolve(image, kernel, boundary="wrap")
    np.testing.assert_allclose(
        frequency.fft_convolve(image, kernel, boundary="wrap"), expected, atol=1e-5
    )


def test_spectrum_of_a_cosine_has_two_peaks_at_its_frequency():
    y, x = np.mgrid[0:64, 0:80]
    wave = (0.5 + 0.25 * np.cos(2 * math.pi * (5 * x / 80 + 3 * y / 64))).astype(np.float32)
    result = frequency.spectrum(wave)
    magnitude = result.magnitude.copy()
    centre = (32, 40)
    assert magnitude[centre] == pytest.approx(0.5 * wave.size, rel=1e-5)  # the mean
    magnitude[centre] = 0
    peaks = {tuple(p) for p in np.argwhere(magnitude > 0.1 * wave.size)}
    assert peaks == {(32 + 3, 40 + 5), (32 - 3, 40 - 5)}
    assert magnitude[32 + 3, 40 + 5] == pytest.approx(0.125 * wave.size, rel=1e-4)
    assert result.log_magnitude.max() == pytest.approx(1.0)


def test_ideal_filters_split_sinusoids_by_frequency():
    x = np.arange(128)
    slow = 0.2 * np.cos(2 * math.pi * 4 * x / 128)  # 0.031 cycles/pixel
    fast = 0.2 * np.cos(2 * math.pi * 40 * x / 128)  # 0.31 cycles/pixel
    image = np.tile(0.5 + slow + fast, (16, 1)).astype(np.float32)
    low = frequency.frequency_filter(image, kind="ideal", band="low", cutoff=0.1)
    high = frequency.frequency_filter(image, kind="ideal", band="high", cutoff=0.1)
    np.testing.assert_allclose(low, np.tile(0.5 + slow, (16, 1)), atol=1e-5)
    np.testing.assert_allclose(high, np.tile(fast, (16, 1)), atol=1e-5)


def test_gaussian_low_pass_is_a_spatial_gaussian_with_wrap():
    image = np.random.default_rng(0).random((48, 60)).astype(np.float32)
    cutoff = 0.05
    found = frequency.frequency_filter(image, kind="gaussian", band="low", cutoff=cutoff)
    # σ = 1 / (2π f_c): the Gaussian's transform e^{-2π²σ²f²} = e^{-f²/2f_c²}
    expected = ndi.gaussian_filter(
        image.astype(np.float64), 1 / (2 * math.pi * cutoff), mode="wrap", truncate=8
    )
    np.testing.assert_allclose(found, expected, atol=1e-5)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match=r"kernel 9×9 is larger than the image 5×5"):
        frequency.fft_convolve(np.zeros((5, 5), np.float32), np.ones((9, 9)), boundary="crop")
    with pytest.raises(gv.ParameterError, match="cutoff"):
        frequency.frequency_filter(np.zeros((5, 5), np.float32), cutoff=0)
