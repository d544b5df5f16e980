"""Even-length taps through the compiled separable core (its passes take odd lengths)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi

from graphvision_plugins.filters import box
from graphvision_plugins.shared.separable import correlate_separable

MODES = {"zero": "constant", "mirror": "reflect", "replicate": "nearest", "wrap": "grid-wrap"}


@pytest.mark.parametrize("size", [2, 4, 6])
@pytest.mark.parametrize("boundary", sorted(MODES))
def test_an_even_box_is_scipys_uniform_filter(size, boundary):
    """Before: size 4 weighted the window [1, 2, 1, 1] / 16 along each axis (its impulse
    response summed to 25/16), since the core read an even length as an odd one."""
    image = np.random.default_rng(size).random((21, 26)).astype(np.float32)
    expected = ndi.uniform_filter(image.astype(np.float64), size, mode=MODES[boundary])
    np.testing.assert_allclose(box(image, size=size, boundary=boundary), expected, atol=1e-6)


def test_even_taps_are_centred_at_half_their_length():
    image = np.random.default_rng(3).random((15, 17))
    taps = np.array([0.1, 0.2, 0.3, 0.4])
    expected = ndi.correlate1d(ndi.correlate1d(image, taps, axis=0), taps, axis=1)
    np.testing.assert_allclose(correlate_separable(image, taps, taps), expected, atol=1e-12)
