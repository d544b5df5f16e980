"""The compiled homography RANSAC against the generic ``fitting.ransac`` loop over
``estimate_homography`` and ``transfer_error`` it replaces: same samples, same inliers,
the same model to rounding (the refit is compiled too)."""

from __future__ import annotations

import numpy as np
import pytest

from graphvision_plugins.fitting import ransac
from graphvision_plugins.geometry._homography import (
    estimate_homography,
    ransac_four_point,
    transfer_error,
)


@pytest.mark.parametrize(("seed", "share"), [(0, 0.3), (1, 0.6), (2, 0.1)])
def test_compiled_homography_ransac_finds_the_generic_loops_inliers(seed, share):
    rng = np.random.default_rng(seed)
    src = rng.uniform(0, 500, (200, 2))
    src[:20] = np.column_stack([np.linspace(0, 500, 20), np.linspace(0, 250, 20)])  # collinear
    H = np.array([[1.1, 0.1, 20], [-0.05, 0.95, 10], [1e-4, 2e-4, 1]])
    dst = (src @ H[:2, :2].T + H[:2, 2]) / (src @ H[2, :2] + H[2, 2])[:, None]
    dst += rng.normal(0, 0.7, dst.shape)
    wrong = rng.random(len(src)) < share
    dst[wrong] = rng.uniform(0, 500, (wrong.sum(), 2))
    generic = ransac(
        len(src),
        4,
        lambda s: estimate_homography(src[s], dst[s]),
        lambda h: transfer_error(h, src, dst),
        3.0,
        refit=lambda i: estimate_homography(src[i], dst[i]),
        confidence=0.995,
        max_iterations=2000,
        seed=seed,
    )
    compiled = ransac_four_point(src, dst, 3.0, confidence=0.995, max_iterations=2000, seed=seed)
    assert compiled.iterations == generic.iterations
    np.testing.assert_array_equal(compiled.inliers, generic.inliers)
    np.testing.assert_allclose(compiled.model, generic.model, rtol=1e-9, atol=1e-12)
