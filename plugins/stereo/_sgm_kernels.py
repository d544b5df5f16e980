"""numba kernels of semi-global matching in two sweeps (imported on first use).

The volume and the sum are disparity-major, ``(rows, count, cols)``. The forward sweep
goes down the rows and aggregates the paths whose predecessor it has already visited,
``(0, 1)``, ``(1, 0)``, ``(1, 1)`` and ``(1, −1)``; the backward sweep goes up with the
opposite four (with 4 paths: the horizontal and vertical ones only). A vertical or
diagonal path advances a whole row at once from its previous row's costs (one SIMD loop
over the row's pixels per disparity, a sentinel row at each end of the range); the
horizontal path goes pixel by pixel on the row turned pixel-major, one SIMD loop over
the disparities per pixel (a band of rows advanced together, SIMD over the rows, was
slower: turning a 16-row band pixel-major misses the cache where a row fits). The sum is in 16-bit
integers (the caller checks that it fits), so the order of the paths does not change it:
the result is ``_kernels.aggregate_path``'s over ``PATHS`` to the bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._match_kernels import resolve_row

__all__ = ["sweep_paths"]


@njit(cache=True, nogil=True, inline="always")
def _start(cost: np.ndarray, out: np.ndarray, total: np.ndarray) -> np.uint16:  # pragma: no cover
    """A path's first pixel: ``out = cost``, added to ``total``; returns min_k."""
    low = np.uint16(65535)
    for k in range(cost.size):
        out[k] = cost[k]
        total[k] = np.uint16(total[k] + cost[k])
        low = min(low, cost[k])
    return low


@njit(cache=True, nogil=True, inline="always")
def _least(a: np.uint16, b: np.uint16) -> np.uint16:  # pragma: no cover
    """The smaller, as a select on 16-bit lanes (no widening)."""
    return a if a < b else b


@njit(cache=True, nogil=True, inline="always")
def _step(
    cost: np.ndarray,
    before: np.ndarray,
    before_min: int,
    out: np.ndarray,
    total: np.ndarray,
    small: int,
    large: int | np.integer,
) -> np.uint16:  # pragma: no cover
    """``out[k] = cost[k] + min(before[k], before[k ± 1] + small, before_min + large)
    − before_min``, added to ``total``; returns min_k out (ends of the range apart).

    In 16-bit lanes: every term fits (the caller bounds the paths' sum), and the
    minimum is at least ``before_min``, so nothing wraps."""
    last = cost.size - 1
    low_before = np.uint16(before_min)
    jump = np.uint16(before_min + large)
    step = np.uint16(small)
    if last == 0:
        value = np.uint16(cost[0] + np.uint16(_least(before[0], jump) - low_before))
        out[0] = value
        total[0] = np.uint16(total[0] + value)
        return value
    here = _least(_least(before[0], np.uint16(before[1] + step)), jump)
    value = np.uint16(cost[0] + np.uint16(here - low_before))
    out[0] = value
    total[0] = np.uint16(total[0] + value)
    low = value
    # slices indexed from 0: ``before[k - 1]`` kept numba's negative-index check in the
    # loop, and then it did not vectorise (one disparity per instruction)
    below, middle, above = before[: last - 1], before[1:last], before[2:]
    costs, outs, totals = cost[1:last], out[1:last], total[1:last]
    for i in range(last - 1):
        side = _least(np.uint16(below[i] + step), np.uint16(above[i] + step))
        here = _least(_least(middle[i], side), jump)
        value = np.uint16(costs[i] + np.uint16(here - low_before))
        outs[i] = value
        totals[i] = np.uint16(totals[i] + value)
        low = _least(low, value)
    here = _least(_least(before[last], np.uint16(before[last - 1] + step)), jump)
    value = np.uint16(cost[last] + np.uint16(here - low_before))
    out[last] = value
    total[last] = np.uint16(total[last] + value)
    return _least(low, value)


@njit(cache=True, nogil=True)
def _transpose(source: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """``out = source.T``, a row of ``source`` at a time."""
    for k in range(source.shape[0]):
        line, column = source[k], out[:, k]
        for x in range(line.size):
            column[x] = line[x]


@njit(cache=True, nogil=True)
def _along_row(
    costs: np.ndarray,
    step_x: int,
    small: int,
    jumps: np.ndarray,
    work: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:  # pragma: no cover
    """The path along a pixel-major row ``costs`` ``(cols, count)`` whose predecessor of
    ``x`` is ``x − step_x`` (visited in that order), added to ``work[2]`` (``work``: path
    costs, their minima, the sum)."""
    cols = costs.shape[0]
    found, found_min, added = work
    for j in range(cols):
        x = j if step_x > 0 else cols - 1 - j
        if j == 0:
            found_min[x] = _start(costs[x], found[x], added[x])
        else:
            px = x - step_x
            low = found_min[px]
            found_min[x] = _step(
                costs[x], found[px], low, found[x], added[x], small, np.int64(jumps[x])
            )


@njit(cache=True, nogil=True)
def _horizontal(
    volume: np.ndarray, total: np.ndarray, small: int, jumps: tuple[np.ndarray, np.ndarray]
) -> None:  # pragma: no cover
    """``total`` = the two paths along the rows, ``(0, 1)`` and ``(0, −1)`` (``jumps``:
    theirs), each row turned pixel-major once for both (the paths stay within a row)."""
    rows, count, cols = volume.shape
    costs = np.empty((cols, count), dtype=np.uint16)
    work = (
        np.empty((cols, count), dtype=np.uint16),
        np.empty(cols, dtype=np.uint16),
        np.empty((cols, count), dtype=np.uint16),
    )
    for y in range(rows):
        _transpose(volume[y], costs)
        work[2][:] = 0
        _along_row(costs, 1, small, jumps[0][y], work)
        _along_row(costs, -1, small, jumps[1][y], work)
        _transpose(work[2], total[y])


@njit(cache=True, nogil=True)
def _across_rows(
    cost: np.ndarray,
    total: np.ndarray,
    step_x: int,
    small: int,
    jumps: np.ndarray,
    first_row: bool,
    before: tuple[np.ndarray, np.ndarray],
    out: tuple[np.ndarray, np.ndarray],
) -> None:  # pragma: no cover
    """A vertical or diagonal path over one disparity-major row ``cost`` ``(count, cols)``:
    pixel ``x`` continues from ``x − step_x`` of the sweep's previous row (``before``:
    path costs with a sentinel row above and below, and their minima; unused on the
    first row), every pixel of the row at once (SIMD over x). ``out`` gets this row's."""
    count, cols = cost.shape
    found, found_min = out
    lo, hi = (0, 0) if first_row else (max(0, step_x), min(cols, cols + step_x))
    for x in range(cols):  # the path starts where its predecessor is outside the image
        if lo <= x < hi:
            continue
        found_min[x] = 65535
        for k in range(count):
            found[k + 1, x] = cost[k, x]
            total[k, x] = np.uint16(total[k, x] + cost[k, x])
            found_min[x] = min(found_min[x], cost[k, x])
    if hi <= lo:
        return
    previous, previous_min = before
    n = hi - lo
    low_before = previous_min[lo - step_x : hi - step_x]
    jump = np.empty(n, dtype=np.uint16)
    penalty = jumps[lo:hi]
    for i in range(n):
        jump[i] = np.uint16(low_before[i] + penalty[i])
    lowest = found_min[lo:hi]
    lowest[:] = 65535
    step = np.uint16(small)
    for k in range(count):
        below = previous[k, lo - step_x : hi - step_x]
        here = previous[k + 1, lo - step_x : hi - step_x]
        above = previous[k + 2, lo - step_x : hi - step_x]
        c, o, t = cost[k, lo:hi], found[k + 1, lo:hi], total[k, lo:hi]
        for i in range(n):
            side = _least(np.uint16(below[i] + step), np.uint16(above[i] + step))
            best = _least(_least(here[i], side), jump[i])
            value = np.uint16(c[i] + np.uint16(best - low_before[i]))
            o[i] = value
            t[i] = np.uint16(t[i] + value)
            lowest[i] = _least(lowest[i], value)


@njit(cache=True, nogil=True)
def _sweep(
    volume: np.ndarray, total: np.ndarray, sign: int, small: int, jumps: np.ndarray
) -> None:  # pragma: no cover
    """Add the paths across rows of one sweep (``sign`` 1 forward, −1 backward) to
    ``total``, row by row: ``(sign, 0)``, ``(sign, sign)``, ``(sign, −sign)`` for
    ``jumps[1:]`` (``jumps[0]``, along the row, is :func:`_horizontal`'s). ``volume`` and
    ``total`` are disparity-major ``(rows, count, cols)``."""
    rows, count, cols = volume.shape
    paths = jumps.shape[0]
    steps_x = (0, 0, sign, -sign)
    previous = np.full((paths, count + 2, cols), 65535 - small, dtype=np.uint16)
    current = previous.copy()  # rows 0 and count + 1: sentinels that never win
    previous_min = np.empty((paths, cols), dtype=np.uint16)
    current_min = np.empty((paths, cols), dtype=np.uint16)
    for i in range(rows):
        y = i if sign > 0 else rows - 1 - i
        for p in range(1, paths):
            _across_rows(
                volume[y],
                total[y],
                steps_x[p],
                small,
                jumps[p, y],
                i == 0,
                (previous[p], previous_min[p]),
                (current[p], current_min[p]),
            )
        previous, current = current, previous
        previous_min, current_min = current_min, previous_min


@njit(cache=True, nogil=True)
def sweep_paths(
    volume: np.ndarray,
    small: int,
    forward_jumps: np.ndarray,
    backward_jumps: np.ndarray,
    d_min: int,
    uniqueness: float,
    subpixel: bool,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """Left and right disparities of the path-aggregated disparity-major ``volume``
    ``(rows, count, cols)``, uint16."""
    rows, _, cols = volume.shape
    total = np.empty_like(volume)
    _horizontal(volume, total, small, (forward_jumps[0], backward_jumps[0]))
    _sweep(volume, total, 1, small, forward_jumps)
    _sweep(volume, total, -1, small, backward_jumps)
    out = np.empty((rows, cols), dtype=np.float32)
    right_out = np.empty((rows, cols), dtype=np.float32)
    for y in range(rows):
        resolve_row(total[y], d_min, uniqueness, subpixel, out[y], right_out[y])
    return out, right_out
