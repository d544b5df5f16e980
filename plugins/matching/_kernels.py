"""numba kernel of brute-force matching: one pass over a block of squared distances.

``np.argpartition`` and two ``take_along_axis`` per row made the block's two
nearest neighbours; this pass keeps the two smallest of each row and, for the
symmetric test, the smallest of each column (the reverse nearest neighbour),
so the reverse search needs no second matrix product.
"""

from __future__ import annotations

import math

from ..shared.jit import njit

__all__ = ["two_smallest"]


@njit(cache=True, nogil=True)
def two_smallest(squared, start, index, value, column_value, column_index):  # pragma: no cover
    """Two smallest of each row of ``squared`` (first index on ties) into ``index`` / ``value``.

    Also lowers ``column_value`` / ``column_index`` to each column's smallest
    entry so far, the row numbered from ``start`` (blocks of rows in turn).
    """
    rows, cols = squared.shape
    for i in range(rows):
        best, second = math.inf, math.inf
        first_j, second_j = 0, 0
        for j in range(cols):
            v = squared[i, j]
            if v < second:
                if v < best:
                    second, second_j = best, first_j
                    best, first_j = v, j
                else:
                    second, second_j = v, j
            if v < column_value[j]:
                column_value[j] = v
                column_index[j] = start + i
        index[i, 0], index[i, 1] = first_j, second_j
        value[i, 0], value[i, 1] = best, second
