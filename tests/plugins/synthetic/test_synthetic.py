"""Synthetic data: seeded, with the statistics and the truth it claims."""

from __future__ import annotations

import numpy as np
import pytest

from graphvision_plugins import synthetic


def test_noise_is_seeded_and_has_the_asked_statistics():
    clean = np.full((200, 200), 0.5, np.float32)
    noisy = synthetic.gaussian_noise(clean, sigma=0.05, seed=3)
    np.testing.assert_array_equal(noisy, synthetic.gaussian_noise(clean, sigma=0.05, seed=3))
    assert not np.array_equal(noisy, synthetic.gaussian_noise(clean, sigma=0.05, seed=4))
    # 40,000 samples: the std estimate is within 2% of sigma (about 6 standard errors)
    assert (noisy - clean).std() == pytest.approx(0.05, rel=0.02)
    sp = synthetic.salt_and_pepper(clean, amount=0.1, salt_ratio=0.25, seed=0)
    hit = sp != 0.5
    assert hit.mean() == pytest.approx(0.1, abs=0.01)
    assert (sp[hit] == 1.0).mean() == pytest.approx(0.25, abs=0.03)
    impulse = synthetic.impulse_noise(clean, amount=0.1, seed=0)
    assert set(np.unique(impulse).tolist()) == {0.5, 1.0}


def test_colour_noise_hits_whole_pixels():
    clean = np.full((50, 50, 3), 0.5, np.float32)
    sp = synthetic.salt_and_pepper(clean, amount=0.2, seed=1)
    changed = sp != 0.5
    assert np.array_equal(changed.any(axis=2), changed.all(axis=2))
