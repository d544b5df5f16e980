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
    """Exact 3×3 median: Paeth's network over sorted column triples, one pass per row.

    With each column sorted into (low, mid, high), the median of the nine is
    the median of (largest low, median of the mids, smallest high) [Paeth].
    The three rows are read where they lie in ``image`` (a zero row for
    ``row_index`` −1), and each window's three columns are sorted in the loop
    that selects its median (a vector of pixels at a time, as OpenCV does):
    sorting each column once into arrays and reading them back three times cost
    more than sorting it three times in registers. Only the windows over a
    border read their columns through ``column_index``. Padded row ``p`` comes
    as the ``p mod 3``-th of the three, the order of the ring of lines the
    kernel once copied the rows into: every comparator keeps its first operand
    on a tie, so between +0 and −0 the median keeps the sign bit it had then.
    """
    rows, cols = out.shape
    width = image.shape[1]
    before = (column_index.size - width) // 2  # 0 for crop
    inside = max(width - 2, 0)  # the windows within the image's columns, from ``before``
    zeros = np.zeros(width, dtype=np.float32)
    for r in range(rows):
        top = _image_row(image, row_index[r + (0 - r) % 3], zeros)
        centre = _image_row(image, row_index[r + (1 - r) % 3], zeros)
        bottom = _image_row(image, row_index[r + (2 - r) % 3], zeros)
        row = out[r]
        _medians_inside(top, centre, bottom, row[before : before + inside])
        for c in range(before):
            row[c] = _median_on_border(top, centre, bottom, column_index, c)
        for c in range(before + inside, cols):
            row[c] = _median_on_border(top, centre, bottom, column_index, c)


@njit(cache=True, nogil=True)
def _image_row(image: np.ndarray, source: int, zeros: np.ndarray) -> np.ndarray:  # pragma: no cover
    """Row ``source`` of ``image``, or ``zeros`` for −1 (the zero boundary)."""
    return image[source] if source >= 0 else zeros


@njit(cache=True, nogil=True, inline="always")
def _sort3(a: float, b: float, c: float) -> tuple[float, float, float]:  # pragma: no cover
    """(low, mid, high) of ``a, b, c``; ``min``/``max`` keep their first operand on a tie."""
    small, large = min(a, b), max(a, b)
    return min(small, c), max(small, min(large, c)), max(large, c)


@njit(cache=True, nogil=True, inline="always")
def _median9(
    t0: float,
    c0: float,
    b0: float,
    t1: float,
    c1: float,
    b1: float,
    t2: float,
    c2: float,
    b2: float,
) -> float:  # pragma: no cover
    """Median of three columns (top, centre, bottom each) by Paeth's network."""
    low0, mid0, high0 = _sort3(t0, c0, b0)
    low1, mid1, high1 = _sort3(t1, c1, b1)
    low2, mid2, high2 = _sort3(t2, c2, b2)
    lows = max(max(low0, low1), low2)
    highs = min(min(high0, high1), high2)
    mids = max(min(mid0, mid1), min(max(mid0, mid1), mid2))
    small, large = min(lows, mids), max(lows, mids)
    return max(small, min(large, highs))


@njit(cache=True, nogil=True)
def _medians_inside(
    top: np.ndarray, centre: np.ndarray, bottom: np.ndarray, row: np.ndarray
) -> None:  # pragma: no cover
    """``row[x]`` = median of columns ``x .. x + 2`` of the three rows (a SIMD loop)."""
    t1, c1, b1, t2, c2, b2 = top[1:], centre[1:], bottom[1:], top[2:], centre[2:], bottom[2:]
    for x in range(row.size):
        row[x] = _median9(top[x], centre[x], bottom[x], t1[x], c1[x], b1[x], t2[x], c2[x], b2[x])


@njit(cache=True, nogil=True)
def _median_on_border(
    top: np.ndarray, centre: np.ndarray, bottom: np.ndarray, column_index: np.ndarray, c: int
) -> float:  # pragma: no cover
    """Median of the window at output column ``c``: padded columns ``c .. c + 2``, each
    image column ``column_index[j]`` (−1: zeros)."""
    j0, j1, j2 = column_index[c], column_index[c + 1], column_index[c + 2]
    return _median9(
        _at(top, j0),
        _at(centre, j0),
        _at(bottom, j0),
        _at(top, j1),
        _at(centre, j1),
        _at(bottom, j1),
        _at(top, j2),
        _at(centre, j2),
        _at(bottom, j2),
    )


@njit(cache=True, nogil=True)
def _at(line: np.ndarray, k: int) -> np.float32:  # pragma: no cover
    """``line[k]``, or a float32 zero for −1."""
    return line[k] if k >= 0 else np.float32(0.0)
