"""Canny's compiled gradient magnitude equals ``np.hypot`` of the float32 gradients (the old
path), to the bit, and so do the edges."""

from __future__ import annotations

import numpy as np
import skimage.data

from graphvision_plugins.edges import canny_edges
from graphvision_plugins.edges._derivatives import gradient_images
from graphvision_plugins.edges._kernels import gradient_magnitude


def test_magnitude_equals_hypot_to_the_bit():
    rng = np.random.default_rng(2)
    for scale in (1.0, 1e-3, 1e3, 1e-20, 1e19):
        dx = (rng.standard_normal((300, 400)) * scale).astype(np.float32)
        dy = (rng.standard_normal((300, 400)) * scale).astype(np.float32)
        dy[0, :50] = 0.0  # one component zero
        np.testing.assert_array_equal(gradient_magnitude(dx, dy), np.hypot(dx, dy))


def test_canny_magnitude_is_the_hypot_of_its_gradients():
    camera = (skimage.data.camera()[::2, ::2] / 255.0).astype(np.float32)
    for sigma in (1.0, 2.5):
        dx, dy = gradient_images(camera, "gaussian", sigma, "mirror")
        _, magnitude = canny_edges(camera, sigma, 0.05, 0.1)
        np.testing.assert_array_equal(magnitude, np.hypot(dx, dy).astype(np.float32))
