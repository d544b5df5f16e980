"""numba kernel of the median filter (imported on first use: compiling costs time)."""

from __future__ import annotations

from collections.abc import Callable
from typing import cast

import numpy as np
from numba.extending import intrinsic

from ..shared.jit import njit
from ._padded_rows import fill_line

__all__ = ["lower", "median_by_network", "upper"]


def _select_codegen(predicate: str) -> Callable:
    """``p <predicate> q ? p : q`` as one LLVM ``fcmp`` and ``select``, written into the
    caller's code (an intrinsic: no call for the compiler to inline). A numba function with
    ``inline="always"`` did the same at run time, but inlining it at each of the 5×5
    network's 200 comparators took 20 s of CPU at the first call in a fresh install."""

    def codegen(context, builder, signature, args):
        p, q = args
        return builder.select(builder.fcmp_ordered(predicate, p, q), p, q)

    return codegen


@intrinsic
def _lower(typingctx, p, q):  # pragma: no cover
    return p(p, q), _select_codegen("<")


@intrinsic
def _upper(typingctx, p, q):  # pragma: no cover
    return p(p, q), _select_codegen(">")


# lower(p, q): the smaller of p, q; ``p < q ? p : q`` is x86's MINPS, one instruction per 8
# lanes (``np.minimum`` adds a NaN test and two blends: four; images are finite, the input
# ports refuse NaN, so the value chosen is the same). upper(p, q): ``p > q ? p : q``, MAXPS.
lower = cast("Callable[[float, float], float]", _lower)
upper = cast("Callable[[float, float], float]", _upper)


@njit(cache=True, nogil=True)
def _compare(
    wires: np.ndarray, lo: int, hi: int, kind: int, width: int
) -> None:  # pragma: no cover
    """One comparator over ``width`` pixels: ``lo`` ← min, ``hi`` ← max (or one of them)."""
    low, high = wires[lo], wires[hi]
    # np.minimum / np.maximum compile to selects without branches (a conditional
    # expression became a branch here, mispredicted about half the time on image data;
    # ``lower`` and ``upper`` too: 2.5 times slower on the 7×7 median); images are
    # finite, so they choose as ``p if p < q else q`` did
    if kind == 0:
        for x in range(width):
            p, q = low[x], high[x]
            low[x] = np.minimum(p, q)
            high[x] = np.maximum(p, q)
    elif kind == 1:
        for x in range(width):
            low[x] = np.minimum(low[x], high[x])
    else:
        for x in range(width):
            high[x] = np.maximum(low[x], high[x])


@njit(cache=True, nogil=True)
def _advance(
    lines: np.ndarray, image: np.ndarray, row_index: np.ndarray, column_index: np.ndarray, r: int
) -> None:  # pragma: no cover
    """Hold padded rows ``r .. r + size − 1`` in the ring ``lines`` (slot: row mod size)."""
    size = lines.shape[0]
    before = (column_index.size - image.shape[1]) // 2  # 0 for crop
    first = 0 if r == 0 else r + size - 1
    for p in range(first, r + size):
        fill_line(lines[p % size], image, row_index[p], column_index, before)


@njit(cache=True, nogil=True)
def median_by_network(
    image: np.ndarray,
    row_index: np.ndarray,
    column_index: np.ndarray,
    column_sort: np.ndarray,
    selection: np.ndarray,
    median_wire: int,
    out: np.ndarray,
    block: int,
) -> None:  # pragma: no cover
    """``out[r, c]`` = median of the padded window at ``r, c``, a column block at a time.

    The image is padded as it is read: padded row ``p`` is image row
    ``row_index[p]`` with columns ``column_index`` (−1: zero), kept in a ring
    of ``size`` lines. Per output row and block: the ``size`` lines are copied
    and sorted down each column by ``column_sort`` (the order of the lines
    does not matter); wire ``rank · size + d`` is then the sorted column
    shifted by ``d``, and ``selection`` leaves the median on ``median_wire``.
    Every comparator runs over the whole block (a SIMD loop).
    """
    rows, cols = out.shape
    size = row_index.size - rows + 1
    lines = np.empty((size, column_index.size), dtype=np.float32)
    columns = np.empty((size, block + size - 1), dtype=np.float32)
    wires = np.empty((size * size, block), dtype=np.float32)
    for r in range(rows):
        _advance(lines, image, row_index, column_index, r)
        for start in range(0, cols, block):
            width = min(block, cols - start)
            span = width + size - 1
            for rank in range(size):
                columns[rank, :span] = lines[rank, start : start + span]
            for t in range(column_sort.shape[0]):
                _compare(columns, column_sort[t, 0], column_sort[t, 1], 0, span)
            for rank in range(size):
                for d in range(size):
                    wires[rank * size + d, :width] = columns[rank, d : d + width]
            for t in range(selection.shape[0]):
                _compare(wires, selection[t, 0], selection[t, 1], selection[t, 2], width)
            out[r, start : start + width] = wires[median_wire, :width]


@njit(cache=True, nogil=True)
def median_3x3(
    image: np.ndarray, row_index: np.ndarray, column_index: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover
    """Exact 3×3 median from sorted column triples, fused into one pass per row.

    With each column sorted into (low, mid, high), the median of the nine is
    the median of (largest low, median of the mids, smallest high) [Paeth].
    Padded rows come from a ring of three lines, as in :func:`median_by_network`.
    """
    rows, cols = out.shape
    lines = np.empty((3, cols + 2), dtype=np.float32)
    low = np.empty(cols + 2, dtype=np.float32)
    mid = np.empty(cols + 2, dtype=np.float32)
    high = np.empty(cols + 2, dtype=np.float32)
    for r in range(rows):
        _advance(lines, image, row_index, column_index, r)
        top, centre, bottom = lines[0], lines[1], lines[2]
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
