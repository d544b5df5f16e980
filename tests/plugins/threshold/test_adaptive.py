"""threshold.adaptive: each pixel against its window's mean minus c."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins.threshold import adaptive


def test_each_pixel_is_compared_with_its_window_mean_minus_c() -> None:
    image = np.full((7, 7), 0.5, np.float32)
    image[3, 3] = 0.59  # the 3×3 windows holding it have mean 0.51
    assert np.argwhere(adaptive(image, window=3, c=0.0)).tolist() == [[3, 3]]
    # c = 0.005: flat pixels (0.5 > 0.495) marked, the 8 around the peak (0.5 <= 0.505) not
    ring = adaptive(image, window=3, c=0.005)
    assert ring.sum() == 49 - 8 and ring[3, 3] and not ring[2:5, 2].any()
    assert adaptive(image, window=3, c=-0.09, foreground="dark")[3, 3]  # 0.59 <= 0.60
    assert not adaptive(image, window=3, c=-0.07, foreground="dark")[3, 3]  # 0.59 > 0.58
    dark = adaptive(image, window=3, c=0.005, foreground="dark")
    np.testing.assert_array_equal(dark, ~ring)  # the complement, ties included


def test_the_gaussian_weights_a_peak_by_its_centre_tap() -> None:
    image = np.zeros((9, 9), np.float32)
    image[4, 4] = 1.0
    sigma = 0.3 * ((5 - 1) * 0.5 - 1.0) + 0.8  # 1.1 for a 5-tap window
    taps = np.exp(-(np.arange(-2, 3) ** 2) / (2 * sigma**2))
    centre = (taps[2] / taps.sum()) ** 2  # the weight of the peak in its own mean
    assert adaptive(image, window=5, c=-(1 - centre) + 1e-6, method="gaussian")[4, 4]
    assert not adaptive(image, window=5, c=-(1 - centre) - 1e-6, method="gaussian")[4, 4]


def test_an_even_window_is_refused_at_validation() -> None:
    spec = gv.discover().node("threshold.adaptive")
    with pytest.raises(ValueError, match=r"window\n.*must be odd so the window is centred"):
        spec.validate_params({"window": 4})
