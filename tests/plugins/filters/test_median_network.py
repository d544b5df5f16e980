"""The selection networks behind filters.median, checked by the 0-1 principle.

A comparator network sorts (selects) every input if it does so for every
input of zeros and ones (Knuth, TAOCP 3, 5.3.4, theorem Z); inputs whose
lists are already sorted are then fixed by how many zeros each list holds.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from graphvision_plugins.filters._median_network import (
    MAX_ONLY,
    MIN_ONLY,
    median_network,
    merge_comparators,
    sort_network,
)


def _run(values: np.ndarray, comparators: np.ndarray) -> np.ndarray:
    """Apply a comparator network to each row of ``values`` (rows are inputs)."""
    wires = values.copy()
    for lo, hi, *kind in comparators:
        low = np.minimum(wires[:, lo], wires[:, hi])
        high = np.maximum(wires[:, lo], wires[:, hi])
        if not kind or kind[0] != MAX_ONLY:
            wires[:, lo] = low
        if not kind or kind[0] != MIN_ONLY:
            wires[:, hi] = high
    return wires


@pytest.mark.parametrize(("m", "n"), list(itertools.product(range(9), range(9))))
def test_odd_even_merge_merges_lists_of_any_lengths(m, n):
    comparators: list[tuple[int, int]] = []
    order = merge_comparators(list(range(m)), list(range(m, m + n)), comparators)
    inputs = np.array(
        [
            [0] * i + [1] * (m - i) + [0] * j + [1] * (n - j)
            for i in range(m + 1)
            for j in range(n + 1)
        ],
        dtype=np.int8,
    ).reshape((m + 1) * (n + 1), m + n)
    merged = _run(inputs, np.array(comparators, dtype=np.int64).reshape(-1, 2))[:, order]
    np.testing.assert_array_equal(merged, np.sort(inputs, axis=1))


@pytest.mark.parametrize("length", [1, 2, 3, 5, 7, 9])
def test_sort_network_sorts_into_wire_order(length):
    inputs = np.array(list(itertools.product((0, 1), repeat=length)), dtype=np.int8)
    np.testing.assert_array_equal(_run(inputs, sort_network(length)), np.sort(inputs, axis=1))


@pytest.mark.parametrize("size", [3, 5])
def test_pruned_network_selects_the_median_of_sorted_columns(size):
    """Every 0-1 window with sorted columns: (size + 1) ** size of them."""
    zeros = np.array(list(itertools.product(range(size + 1), repeat=size)))
    ranks = np.arange(size)
    # wire rank·size + column holds 1 when rank >= zeros in that column
    inputs = (ranks[None, :, None] >= zeros[:, None, :]).astype(np.int8).reshape(len(zeros), -1)
    selection, median_wire = median_network(size)
    expected = np.sort(inputs, axis=1)[:, size * size // 2]
    np.testing.assert_array_equal(_run(inputs, selection)[:, median_wire], expected)


@pytest.mark.parametrize("size", [3, 5, 7])
def test_pruning_drops_comparators_of_the_full_merge(size):
    full: list[tuple[int, int]] = []
    columns = [list(range(column, size * size, size)) for column in range(size)]
    while len(columns) > 1:  # the same balanced tree of merges, unpruned
        merged = [
            merge_comparators(a, b, full) for a, b in zip(columns[::2], columns[1::2], strict=False)
        ]
        columns = merged + columns[len(merged) * 2 :]
    selection, _ = median_network(size)
    assert len(selection) < len(full)
    assert set(map(tuple, selection[:, :2].tolist())) <= set(full)
