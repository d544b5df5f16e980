"""numba kernel of the median filter (imported on first use: compiling costs time)."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["median_by_network"]


@njit(cache=True, nogil=True)
def _compare(
    wires: np.ndarray, lo: int, hi: int, kind: int, width: int
) -> None:  # pragma: no cover
    """One comparator over ``width`` pixels: ``lo`` ← min, ``hi`` ← max (or one of them)."""
    low, high = wires[lo], wires[hi]
    if kind == 0:
        for x in range(width):
            p, q = low[x], high[x]
            low[x] = p if p < q else q
            high[x] = q if p < q else p
    elif kind == 1:
        for x in range(width):
            p, q = low[x], high[x]
            low[x] = p if p < q else q
    else:
        for x in range(width):
            p, q = low[x], high[x]
            high[x] = q if p < q else p


@njit(cache=True, nogil=True)
def median_by_network(
    padded: np.ndarray,
    size: int,
    column_sort: np.ndarray,
    selection: np.ndarray,
    median_wire: int,
    out: np.ndarray,
    block: int,
) -> None:  # pragma: no cover
    """``out[r, c]`` = median of ``padded[r : r + size, c : c + size]``, a column block at a time.

    Per output row and block: the ``size`` rows are copied and sorted down each
    column by ``column_sort``; wire ``rank · size + d`` is then the sorted column
    shifted by ``d``, and ``selection`` leaves the median on ``median_wire``.
    Every comparator runs over the whole block (a SIMD loop).
    """
    rows, cols = out.shape
    columns = np.empty((size, block + size - 1), dtype=np.float32)
    wires = np.empty((size * size, block), dtype=np.float32)
    for r in range(rows):
        for start in range(0, cols, block):
            width = min(block, cols - start)
            span = width + size - 1
            for rank in range(size):
                columns[rank, :span] = padded[r + rank, start : start + span]
            for t in range(column_sort.shape[0]):
                _compare(columns, column_sort[t, 0], column_sort[t, 1], 0, span)
            for rank in range(size):
                for d in range(size):
                    wires[rank * size + d, :width] = columns[rank, d : d + width]
            for t in range(selection.shape[0]):
                _compare(wires, selection[t, 0], selection[t, 1], selection[t, 2], width)
            out[r, start : start + width] = wires[median_wire, :width]


@njit(cache=True, nogil=True)
def median_3x3(padded: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """Exact 3×3 median from sorted column triples, fused into one pass per row.

    With each column sorted into (low, mid, high), the median of the nine is
    the median of (largest low, median of the mids, smallest high) [Paeth].
    """
    rows, cols = out.shape
    low = np.empty(cols + 2, dtype=np.float32)
    mid = np.empty(cols + 2, dtype=np.float32)
    high = np.empty(cols + 2, dtype=np.float32)
    for r in range(rows):
        top, centre, bottom = padded[r], padded[r + 1], padded[r + 2]
        for x in range(cols + 2):
            a, b, c = top[x], centre[x], bottom[x]
            small, large = min(a, b), max(a, b)
            low[x] = min(small, c)
            high[x] = max(large, c)
            mid[x] = max(small, min(large, c))
        row = out[r]
        for x in range(cols):
            lows = max(max(low[x], low[x + 1]), low[x + 2])
            highs = min(min(high[x], high[x + 1]), high[x + 2])
            a, b, c = mid[x], mid[x + 1], mid[x + 2]
            mids = max(min(a, b), min(max(a, b), c))
            small, large = min(lows, mids), max(lows, mids)
            row[x] = max(small, min(large, highs))
