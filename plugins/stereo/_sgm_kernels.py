"""numba kernels of semi-global matching in two sweeps (imported on first use).

The forward sweep visits the pixels row by row from the top left and aggregates the
paths whose predecessor it has already visited, ``(0, 1)``, ``(1, 0)``, ``(1, 1)`` and
``(1, −1)``; the backward sweep from the bottom right does the opposite four (with 4
paths: the horizontal and vertical ones only). Each path's costs of the previous row
(and, for the horizontal path, of the previous pixel) stay in row buffers, so the cost
volume is read twice and the sum written twice, instead of once per path. The sum is in
16-bit integers (the caller checks that it fits), so the order of the paths does not
change it: the result is ``_kernels.aggregate_path``'s over ``PATHS`` to the bit. Each
row is resolved (winner take all, and the right image's winners) as soon as the
backward sweep has finished it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._match_kernels import resolve_row

__all__ = ["sweep_paths"]


@njit(cache=True, nogil=True, inline="always")
def _start(cost: np.ndarray, out: np.ndarray, total: np.ndarray) -> int:  # pragma: no cover
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
    large: int,
) -> int:  # pragma: no cover
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
    for k in range(1, last):
        side = _least(np.uint16(before[k - 1] + step), np.uint16(before[k + 1] + step))
        here = _least(_least(before[k], side), jump)
        value = np.uint16(cost[k] + np.uint16(here - low_before))
        out[k] = value
        total[k] = np.uint16(total[k] + value)
        low = _least(low, value)
    here = _least(_least(before[last], np.uint16(before[last - 1] + step)), jump)
    value = np.uint16(cost[last] + np.uint16(here - low_before))
    out[last] = value
    total[last] = np.uint16(total[last] + value)
    return _least(low, value)


@njit(cache=True, nogil=True)
def _row_path(
    volume: np.ndarray,
    total: np.ndarray,
    y: int,
    step: tuple[int, int],
    small: int,
    jumps: np.ndarray,
    buffers: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> None:  # pragma: no cover
    """One path over row ``y``: the predecessor of ``x`` is ``x − step_x`` in the
    previous row of the sweep (``step_y ≠ 0``) or in this row (``step_y = 0``, visited in
    the path's direction); ``buffers`` are (previous, previous_min, current, current_min)."""
    rows, cols, _ = volume.shape
    previous, previous_min, current, current_min = buffers
    step_y, step_x = step
    before, before_min = (current, current_min) if step_y == 0 else (previous, previous_min)
    first_row = y - step_y < 0 or y - step_y >= rows
    for j in range(cols):
        x = j if step_x >= 0 else cols - 1 - j
        px = x - step_x
        cost, here = volume[y, x], total[y, x]
        if first_row or px < 0 or px >= cols:
            current_min[x] = _start(cost, current[x], here)
        else:
            current_min[x] = _step(
                cost, before[px], before_min[px], current[x], here, small, np.int64(jumps[y, x])
            )


@njit(cache=True, nogil=True)
def _sweep(
    volume: np.ndarray, total: np.ndarray, sign: int, small: int, jumps: np.ndarray
) -> None:  # pragma: no cover
    """Aggregate the ``jumps.shape[0]`` paths of one sweep (``sign`` 1 forward, −1
    backward) into ``total``, row by row, path by path; ``jumps[p]`` are path ``p``'s
    jump penalties."""
    rows, cols, count = volume.shape
    paths = jumps.shape[0]
    steps = ((0, sign), (sign, 0), (sign, sign), (sign, -sign))
    previous = np.empty((paths, cols, count), dtype=volume.dtype)
    current = np.empty((paths, cols, count), dtype=volume.dtype)
    previous_min = np.empty((paths, cols), dtype=np.uint16)
    current_min = np.empty((paths, cols), dtype=np.uint16)
    for i in range(rows):
        y = i if sign > 0 else rows - 1 - i
        for p in range(paths):
            buffers = (previous[p], previous_min[p], current[p], current_min[p])
            _row_path(volume, total, y, steps[p], small, jumps[p], buffers)
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
    """Left and right disparities of the path-aggregated ``volume`` (uint16)."""
    rows, cols, _ = volume.shape
    total = np.zeros_like(volume)
    _sweep(volume, total, 1, small, forward_jumps)
    _sweep(volume, total, -1, small, backward_jumps)
    out = np.empty((rows, cols), dtype=np.float32)
    right_out = np.empty((rows, cols), dtype=np.float32)
    costs = np.empty((volume.shape[2], cols), dtype=volume.dtype)
    for y in range(rows):
        costs[:] = total[y].T
        resolve_row(costs, d_min, uniqueness, subpixel, out[y], right_out[y])
    return out, right_out
