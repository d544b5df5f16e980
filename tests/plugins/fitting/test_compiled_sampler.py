"""The compiled RANSAC loops draw NumPy's samples: ``draw_sample`` against
``Generator.choice(count, size, replace=False)`` and the sample count against
``ransac_iterations``."""

from __future__ import annotations

import numpy as np
import pytest

from graphvision_plugins.fitting._kernels import draw_sample, iterations_needed
from graphvision_plugins.fitting._ransac import ransac_iterations


@pytest.mark.parametrize(
    ("count", "size"), [(8, 8), (9, 8), (390, 8), (10_000, 8), (12_000, 7), (300, 4), (5, 2)]
)
def test_samples_are_those_of_generator_choice(count, size):
    for seed in range(3):
        ours, numpy = np.random.default_rng(seed), np.random.default_rng(seed)
        sample = np.empty(size, np.int64)
        for _ in range(200):
            draw_sample(ours, count, sample)
            np.testing.assert_array_equal(sample, numpy.choice(count, size=size, replace=False))
        assert ours.random() == numpy.random()  # the bit streams are in the same state


def test_the_sample_count_is_ransac_iterations():
    for outliers in np.linspace(0.0, 0.99, 199):
        for size in (2, 4, 8):
            for confidence in (0.99, 0.999):
                expected = min(ransac_iterations(float(outliers), size, confidence), 10**9)
                assert min(iterations_needed(outliers, size, confidence), 10**9) == expected
