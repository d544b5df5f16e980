"""Brute-force matching (one compiled pass over the distances) against an exhaustive search."""

from __future__ import annotations

import numpy as np
import pytest

from graphvision_plugins import matching


def exhaustive(a: np.ndarray, b: np.ndarray):
    """All distances in float64: two nearest of each row of a, nearest row of a for each of b."""
    distance = np.linalg.norm(a[:, None, :].astype(np.float64) - b[None, :, :], axis=2)
    order = np.argsort(distance, axis=1, kind="stable")[:, :2]
    return order, np.take_along_axis(distance, order, axis=1), distance.argmin(axis=0)


@pytest.mark.parametrize("seed", range(2))
def test_match_equals_an_exhaustive_search(seed):
    rng = np.random.default_rng(seed)
    a = rng.random((300, 16)).astype(np.float32)
    b = np.vstack([a[:120] + rng.normal(0, 0.01, (120, 16)), rng.random((80, 16))])
    b = b.astype(np.float32)
    order, distance, back = exhaustive(a, b)
    index, found = matching.nearest_two(a, b)
    np.testing.assert_array_equal(index, order)
    np.testing.assert_allclose(found, distance, rtol=1e-4, atol=1e-4)
    result = matching.match(a, b, ratio=0.8, symmetric=True)
    keep = (distance[:, 0] < 0.8 * distance[:, 1]) & (back[order[:, 0]] == np.arange(len(a)))
    assert sorted(map(tuple, result.pairs)) == sorted(
        (i, order[i, 0]) for i in np.flatnonzero(keep)
    )
    assert len(result) > 100  # the perturbed copies match themselves
    one_way = matching.match(a, b, ratio=0.8, symmetric=False)
    assert len(one_way) == int((distance[:, 0] < 0.8 * distance[:, 1]).sum())


def test_one_train_row_has_an_infinitely_far_second_neighbour():
    a = np.array([[0.0, 0.0], [3.0, 4.0]], np.float32)
    index, distance = matching.nearest_two(a, a[1:])
    np.testing.assert_array_equal(index, [[0, 0], [0, 0]])
    np.testing.assert_allclose(distance, [[5.0, np.inf], [0.0, np.inf]])
