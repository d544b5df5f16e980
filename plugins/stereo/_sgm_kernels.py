"""numba kernels of semi-global matching in two sweeps (imported on first use).

The volume and the sum are disparity-major, ``(rows, count, cols)``. The forward sweep
goes down the rows: it makes each row's block-summed census costs
(``_match_kernels``' running sums, :func:`census_sweep_paths`), aggregates the two paths
along the row and the paths whose predecessor it has already visited, ``(1, 0)``,
``(1, 1)`` and ``(1, −1)``, while the row is in cache; the backward sweep goes up with
the opposite three (with 4 paths: the vertical ones only) and resolves each row as soon
as it is final. Two passes over the volume, not the four of separate volume, horizontal,
forward and backward passes. A vertical or diagonal path advances a whole row at once
from its previous row's costs (one SIMD loop over the row's pixels per disparity, a
sentinel row at each end of the range); the horizontal path goes pixel by pixel on the
row turned pixel-major, one SIMD loop over the disparities per pixel (a band of rows
advanced together, SIMD over the rows, was slower: turning a 16-row band pixel-major
misses the cache where a row fits). The sum is in 16-bit integers (the caller checks
that it fits), so the order of the paths does not change it: the result is
``_kernels.aggregate_path``'s over ``PATHS`` to the bit."""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit
from ._match_kernels import _across, _block_rows, _next_columns
from ._resolve_kernels import resolve_row

__all__ = ["census_sweep_paths", "sweep_paths"]


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
def _to_pixels(source: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """``out = source.T`` (``(count, cols)`` → ``(cols, count)``): four disparity rows
    packed into one 64-bit word per pixel (one store for four values, little-endian as
    the uint16 row of ``out`` reads it), the rows beyond a multiple of four one by one."""
    count, cols = source.shape
    words = count // 4 if count % 4 == 0 else 0  # else a row of ``out`` is no whole word
    wide = np.empty((cols, 0), dtype=np.uint64)
    if words > 0:
        wide = out.reshape(-1).view(np.uint64).reshape((cols, words))
    for w in range(words):
        a, b = source[4 * w], source[4 * w + 1]
        c, d = source[4 * w + 2], source[4 * w + 3]
        column = wide[:, w]
        for x in range(cols):
            column[x] = (
                np.uint64(a[x])
                | (np.uint64(b[x]) << np.uint64(16))
                | (np.uint64(c[x]) << np.uint64(32))
                | (np.uint64(d[x]) << np.uint64(48))
            )
    for k in range(4 * words, count):
        line, column = source[k], out[:, k]
        for x in range(cols):
            column[x] = line[x]


@njit(cache=True, nogil=True)
def _along_both(
    costs: np.ndarray,
    small: int,
    jumps: tuple[np.ndarray, np.ndarray],
    work: tuple[np.ndarray, ...],
) -> None:  # pragma: no cover
    """The paths ``(0, 1)`` and ``(0, −1)`` along a pixel-major row ``costs``
    ``(cols, count)``, added to ``work[4]`` (``work``: each path's costs and minima, the
    sum): one step of each per iteration, from either end, so that the processor
    overlaps the two chains of dependent steps."""
    cols = costs.shape[0]
    forward, forward_min, backward, backward_min, added = work
    last = cols - 1
    forward_min[0] = _start(costs[0], forward[0], added[0])
    backward_min[last] = _start(costs[last], backward[last], added[last])
    ahead, behind = jumps
    for j in range(1, cols):
        x, y = j, last - j
        forward_min[x] = _step(
            costs[x], forward[x - 1], forward_min[x - 1], forward[x], added[x], small,
            np.int64(ahead[x]),
        )  # fmt: skip
        backward_min[y] = _step(
            costs[y], backward[y + 1], backward_min[y + 1], backward[y], added[y], small,
            np.int64(behind[y]),
        )  # fmt: skip


@njit(cache=True, nogil=True)
def _horizontal_buffers(count: int, cols: int) -> tuple[np.ndarray, ...]:  # pragma: no cover
    """The pixel-major row, each path's costs and minima, and the row's sum."""
    return (
        np.empty((cols, count), dtype=np.uint16),
        np.empty((cols, count), dtype=np.uint16),
        np.empty(cols, dtype=np.uint16),
        np.empty((cols, count), dtype=np.uint16),
        np.empty(cols, dtype=np.uint16),
        np.empty((cols, count), dtype=np.uint16),
    )


@njit(cache=True, nogil=True)
def _horizontal_row(
    cost: np.ndarray,
    total: np.ndarray,
    small: int,
    jumps: tuple[np.ndarray, np.ndarray],
    buffers: tuple[np.ndarray, ...],
) -> None:  # pragma: no cover
    """``total`` (a disparity-major row) = the two paths along the row, ``(0, 1)`` and
    ``(0, −1)`` (``jumps``: this row's of each), the row turned pixel-major once for both
    (the paths stay within a row)."""
    costs, added = buffers[0], buffers[5]
    _to_pixels(cost, costs)
    added[:] = 0
    _along_both(costs, small, jumps, buffers[1:])
    _transpose(added, total)


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
def _sweep_state(
    paths: int, count: int, cols: int, small: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """A sweep's previous and current path costs (rows 0 and ``count + 1``: sentinels that
    never win) and their minima, per path."""
    previous = np.full((paths, count + 2, cols), 65535 - small, dtype=np.uint16)
    minima = np.empty((paths, cols), dtype=np.uint16)
    return previous, previous.copy(), minima, minima.copy()


@njit(cache=True, nogil=True)
def _sweep_row(
    cost: np.ndarray,
    total: np.ndarray,
    i: int,
    y: int,
    sign: int,
    small: int,
    jumps: np.ndarray,
    state: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """Add row ``y`` (the sweep's ``i``-th; ``sign`` 1 forward, −1 backward) of the paths
    across rows, ``(sign, 0)``, ``(sign, sign)``, ``(sign, −sign)`` for ``jumps[1:]``
    (``jumps[0]``, along the row, is :func:`_horizontal_row`'s), to ``total``; returns
    the state for the next row."""
    previous, current, previous_min, current_min = state
    steps_x = (0, 0, sign, -sign)
    for p in range(1, jumps.shape[0]):
        _across_rows(
            cost,
            total,
            steps_x[p],
            small,
            jumps[p, y],
            i == 0,
            (previous[p], previous_min[p]),
            (current[p], current_min[p]),
        )
    return current, previous, current_min, previous_min


@njit(cache=True, nogil=True)
def _backward_resolve(
    volume: np.ndarray,
    total: np.ndarray,
    small: int,
    jumps: np.ndarray,
    d_min: int,
    select: tuple[float, bool],
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """The backward sweep, each row resolved (left and right winners) as soon as it is
    final, while it is in cache."""
    rows, count, cols = volume.shape
    out = np.empty((rows, cols), dtype=np.float32)
    right_out = np.empty((rows, cols), dtype=np.float32)
    state = _sweep_state(jumps.shape[0], count, cols, small)
    for i in range(rows):
        y = rows - 1 - i
        state = _sweep_row(volume[y], total[y], i, y, -1, small, jumps, state)
        resolve_row(total[y], d_min, select[0], select[1], out[y], right_out[y])
    return out, right_out


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
    rows, count, cols = volume.shape
    total = np.empty_like(volume)
    buffers = _horizontal_buffers(count, cols)
    state = _sweep_state(forward_jumps.shape[0], count, cols, small)
    for y in range(rows):
        _horizontal_row(
            volume[y], total[y], small, (forward_jumps[0, y], backward_jumps[0, y]), buffers
        )
        state = _sweep_row(volume[y], total[y], y, y, 1, small, forward_jumps, state)
    return _backward_resolve(volume, total, small, backward_jumps, d_min, (uniqueness, subpixel))


@njit(cache=True, nogil=True)
def census_sweep_paths(
    signatures: tuple[np.ndarray, np.ndarray],
    search: tuple[int, int, int, int],
    small: int,
    forward_jumps: np.ndarray,
    backward_jumps: np.ndarray,
    select: tuple[float, bool],
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """:func:`sweep_paths` of ``census_volume(*signatures, *search)`` (``search``:
    ``d_min, count, outside, half``), each row's block sums made in the forward sweep,
    just before its paths along and down the row: two passes over the volume, not four."""
    left, right = signatures
    d_min, count, outside, half = search
    rows, cols = left.shape
    volume = np.empty((rows, count, cols), dtype=np.uint16)
    total = np.empty_like(volume)
    ring, columns = _block_rows(left, right, d_min, count, outside, half)
    buffers = _horizontal_buffers(count, cols)
    state = _sweep_state(forward_jumps.shape[0], count, cols, small)
    for y in range(rows):
        if y > 0:
            _next_columns(left, right, d_min, outside, half, y, ring, columns)
        _across(columns, half, volume[y])
        _horizontal_row(
            volume[y], total[y], small, (forward_jumps[0, y], backward_jumps[0, y]), buffers
        )
        state = _sweep_row(volume[y], total[y], y, y, 1, small, forward_jumps, state)
    return _backward_resolve(volume, total, small, backward_jumps, d_min, select)
