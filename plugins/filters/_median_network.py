"""Selection networks for the median of a ``k × k`` window whose columns are sorted.

A comparator ``(lo, hi)`` puts the smaller of two wires on ``lo`` and the
larger on ``hi``. Batcher's odd-even merge joins two sorted lists of any
lengths :math:`m, n` with comparators only: merge the odd-indexed elements
into :math:`v`, the even-indexed into :math:`w`, then

.. math:: z = v_1,\\ w_1 \\wedge v_2,\\ w_1 \\vee v_2,\\ w_2 \\wedge v_3,\\ \\dots

Sorting each column of the window (a network on ``k`` wires) and merging the
``k`` sorted columns pairwise sorts the window; the median is the wire at
rank :math:`\\lfloor k^2 / 2 \\rfloor`. Walking the merge backwards from that
wire keeps only the comparators it depends on, and only the half (min or max)
whose result is read later, as Adams does for his separable sorting networks.
Columns are sorted once and shared by the ``k`` windows that contain them.

References
----------
.. [1] D. E. Knuth, *The Art of Computer Programming*, vol. 3, 2nd ed., 1998,
   section 5.3.4 (Batcher's merge exchange for any :math:`m, n`).
.. [2] A. Adams, "Fast median filters using separable sorting networks",
   ACM Trans. Graph. 40(4), 2021.
"""

from __future__ import annotations

from functools import cache

import numpy as np

__all__ = ["BOTH", "MAX_ONLY", "MIN_ONLY", "median_network", "merge_comparators", "sort_network"]

BOTH, MIN_ONLY, MAX_ONLY = 0, 1, 2


def merge_comparators(
    first: list[int], second: list[int], comparators: list[tuple[int, int]]
) -> list[int]:
    """Append Batcher's odd-even merge of two sorted wire lists; return the merged order."""
    if not first or not second:
        return first + second
    if len(first) == 1 and len(second) == 1:
        comparators.append((first[0], second[0]))
        return [first[0], second[0]]
    odd = merge_comparators(first[0::2], second[0::2], comparators)
    even = merge_comparators(first[1::2], second[1::2], comparators)
    merged = [odd[0]]
    for index, wire in enumerate(even):
        if index + 1 < len(odd):
            comparators.append((wire, odd[index + 1]))
            merged += [wire, odd[index + 1]]
        else:
            merged.append(wire)
    merged += odd[len(even) + 1 :]
    return merged


def _merge_all(lists: list[list[int]], comparators: list[tuple[int, int]]) -> list[int]:
    """Merge sorted wire lists pairwise, as a balanced tree."""
    while len(lists) > 1:
        paired = [
            merge_comparators(lists[i], lists[i + 1], comparators)
            for i in range(0, len(lists) - 1, 2)
        ]
        lists = paired + ([lists[-1]] if len(lists) % 2 else [])
    return lists[0]


@cache
def sort_network(length: int) -> np.ndarray:
    """Comparators ``(lo, hi)`` (rows of an int64 array) sorting ``length`` wires ascending."""
    comparators: list[tuple[int, int]] = []
    _merge_all([[wire] for wire in range(length)], comparators)  # ends in wire order
    return np.array(comparators, dtype=np.int64).reshape(-1, 2)


@cache
def median_network(size: int) -> tuple[np.ndarray, int]:
    """The pruned network giving the median of ``size²`` wires in ``size`` sorted columns.

    Wire ``rank · size + column`` holds the ``rank``-th smallest value of the
    window's ``column``-th column.

    Returns
    -------
    comparators : (M, 3) int64 ndarray
        ``(lo, hi, kind)`` in execution order; ``kind`` is ``BOTH``,
        ``MIN_ONLY`` (only ``lo`` is written) or ``MAX_ONLY`` (only ``hi``).
    median_wire : int
        The wire that holds the median once the network has run.
    """
    columns = [[rank * size + column for rank in range(size)] for column in range(size)]
    comparators: list[tuple[int, int]] = []
    order = _merge_all(columns, comparators)
    median_wire = order[size * size // 2]
    needed = {median_wire}
    kept: list[tuple[int, int, int]] = []
    for lo, hi in reversed(comparators):
        wants_lo, wants_hi = lo in needed, hi in needed
        if not (wants_lo or wants_hi):
            continue
        kind = BOTH if wants_lo and wants_hi else (MIN_ONLY if wants_lo else MAX_ONLY)
        kept.append((lo, hi, kind))
        needed.update((lo, hi))
    return np.array(kept[::-1], dtype=np.int64).reshape(-1, 3), median_wire
