"""Canny's one-pass suppression and flood equal the two-step form (suppression, then
8-connected components of the kept pixels that hold a strong one) to the bit."""

from __future__ import annotations

import numpy as np
import skimage.data
from scipy import ndimage

from graphvision_plugins.edges import canny_edges, non_maximum_suppression
from graphvision_plugins.edges._derivatives import gradient_images


def _two_step(image, sigma, low, high, thresholds):
    """Suppression, then hysteresis by scipy's labelling (the reference)."""
    dx, dy = gradient_images(image, "gaussian", sigma, "mirror")
    magnitude = np.hypot(dx, dy).astype(np.float32)
    if thresholds == "quantile":
        low, high = (float(q) for q in np.quantile(magnitude, [low, high]))
    thin = non_maximum_suppression(dx, dy, magnitude, low)
    labels, _ = ndimage.label(thin, structure=np.ones((3, 3)))
    seeded = np.unique(labels[thin & (magnitude >= np.float32(high))])
    return np.isin(labels, seeded[seeded > 0])


def test_one_pass_edges_equal_labelled_hysteresis():
    rng = np.random.default_rng(7)
    images = [
        (skimage.data.camera() / 255.0).astype(np.float32),
        (skimage.data.coins() / 255.0).astype(np.float32),
        # random blocks plus noise: many junctions and weak chains branching off strong ones
        (np.kron(rng.random((12, 17)), np.ones((10, 10))) + 0.05 * rng.random((120, 170))).astype(
            np.float32
        ),
    ]
    cases = [(1.0, 0.1, 0.2, "absolute"), (2.0, 0.05, 0.1, "absolute"), (1.0, 0.7, 0.9, "quantile")]
    for image in images:
        for sigma, low, high, thresholds in cases:
            edges, _ = canny_edges(image, sigma, low, high, thresholds)
            expected = _two_step(image, sigma, low, high, thresholds)
            assert expected.any()
            np.testing.assert_array_equal(edges, expected)
