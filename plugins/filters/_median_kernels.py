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


# columns of the 3×3 median per pass: its sorted triples (3 · 1 KB) stay in L1 beside the rows
_SPAN = 256


@njit(cache=True, nogil=True)
def median_3x3(
    image: np.ndarray, row_index: np.ndarray, column_index: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover
    """Exact 3×3 median from sorted column triples, a block of columns at a time.

    With each column sorted into (low, mid, high), the median of the nine is
    the median of (largest low, median of the mids, smallest high) [Paeth].
    The three rows are read where they lie in ``image`` (a zero row for
    ``row_index`` −1) and only the border columns through ``column_index``;
    the triples of ``_SPAN`` columns are sorted into arrays that stay in L1
    and selected from at once. Padded row ``p`` comes as the ``p mod 3``-th of
    the three, the order of the ring of lines the kernel once copied them into:
    every comparator keeps its first operand on a tie, so between +0 and −0 the
    median keeps the sign bit it had then.
    """
    rows, cols = out.shape
    zeros = np.zeros(image.shape[1], dtype=np.float32)
    triples = np.empty((3, _SPAN + 2), dtype=np.float32)
    for r in range(rows):
        top = _image_row(image, row_index[r + (0 - r) % 3], zeros)
        centre = _image_row(image, row_index[r + (1 - r) % 3], zeros)
        bottom = _image_row(image, row_index[r + (2 - r) % 3], zeros)
        row = out[r]
        for start in range(0, cols, _SPAN):
            width = min(_SPAN, cols - start)
            _sort_columns(top, centre, bottom, column_index, start, width + 2, triples)
            _select_3x3(triples[0], triples[1], triples[2], row[start : start + width])


@njit(cache=True, nogil=True)
def _image_row(image: np.ndarray, source: int, zeros: np.ndarray) -> np.ndarray:  # pragma: no cover
    """Row ``source`` of ``image``, or ``zeros`` for −1 (the zero boundary)."""
    return image[source] if source >= 0 else zeros


@njit(cache=True, nogil=True)
def _sort3(a: float, b: float, c: float) -> tuple[float, float, float]:  # pragma: no cover
    """(low, mid, high) of ``a, b, c``: on a tie, the first of them in that order."""
    small, large = min(a, b), max(a, b)
    return min(small, c), max(small, min(large, c)), max(large, c)


@njit(cache=True, nogil=True, inline="always")
def _sort_columns(
    top: np.ndarray,
    centre: np.ndarray,
    bottom: np.ndarray,
    column_index: np.ndarray,
    start: int,
    span: int,
    triples: np.ndarray,
) -> None:  # pragma: no cover
    """``triples[:, i]`` = sorted (low, mid, high) of padded column ``start + i``, ``i <
    span``: image column ``start + i − before`` inside, ``column_index``'s (−1: zeros) on
    the border."""
    width = top.size
    before = (column_index.size - width) // 2  # 0 for crop
    first = max(before - start, 0)  # the first i inside the image, and one past the last
    last = min(before + width - start, span)
    shift = start + first - before
    a, b, c = top[shift:], centre[shift:], bottom[shift:]
    low, mid, high = triples[0, first:], triples[1, first:], triples[2, first:]
    for i in range(last - first):
        low[i], mid[i], high[i] = _sort3(a[i], b[i], c[i])
    for i in range(first):
        _sort_border(top, centre, bottom, column_index[start + i], triples[:, i])
    for i in range(last, span):
        _sort_border(top, centre, bottom, column_index[start + i], triples[:, i])


@njit(cache=True, nogil=True)
def _sort_border(
    top: np.ndarray, centre: np.ndarray, bottom: np.ndarray, k: int, triple: np.ndarray
) -> None:  # pragma: no cover
    """``triple`` = sorted column ``k`` of the three rows (−1: zeros)."""
    if k >= 0:
        triple[0], triple[1], triple[2] = _sort3(top[k], centre[k], bottom[k])
    else:
        triple[:] = 0.0


@njit(cache=True, nogil=True, inline="always")
def _select_3x3(
    low: np.ndarray, mid: np.ndarray, high: np.ndarray, row: np.ndarray
) -> None:  # pragma: no cover
    """``row[x]`` = median of (largest low, median of the mids, smallest high) over the
    sorted triples ``x, x + 1, x + 2``."""
    for x in range(row.size):
        lows = max(max(low[x], low[x + 1]), low[x + 2])
        highs = min(min(high[x], high[x + 1]), high[x + 2])
        a, b, c = mid[x], mid[x + 1], mid[x + 2]
        mids = max(min(a, b), min(max(a, b), c))
        small, large = min(lows, mids), max(lows, mids)
        row[x] = max(small, min(large, highs))
