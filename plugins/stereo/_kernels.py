"""numba kernels of the disparity search (imported on first use: compiling costs time).

The cost volume is ``(rows, cols, D)`` with ``cost[y, x, k]`` the cost of matching
left pixel ``(y, x)`` with right pixel ``(y, x − d_min − k)``; a right pixel outside
the image costs the cost's maximum. Census costs are uint16 (bit counts), the others
float32; every kernel is compiled for the dtype it is given, so semi-global matching
of census costs with integer penalties runs in 16-bit integers, three times as fast
as in float32 and with the same result.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..shared.jit import njit

__all__ = [
    "aggregate_path",
    "box_sum",
    "census",
    "census_costs",
    "right_disparity",
    "speckle_filter",
    "winner_take_all",
]


@njit(cache=True, nogil=True, parallel=True)
def census(image: np.ndarray, half_rows: int, half_cols: int) -> np.ndarray:  # pragma: no cover
    """Census signature: one bit per window pixel, set when it is darker than the centre.

    Pixels outside the image repeat the nearest edge pixel. At most 63 bits
    (the window without its centre).
    """
    rows, cols = image.shape
    out = np.zeros((rows, cols), dtype=np.uint64)
    for y in prange(rows):
        for x in range(cols):
            centre = image[y, x]
            bits = np.uint64(0)
            for dy in range(-half_rows, half_rows + 1):
                yy = min(max(y + dy, 0), rows - 1)
                for dx in range(-half_cols, half_cols + 1):
                    if dy == 0 and dx == 0:
                        continue
                    xx = min(max(x + dx, 0), cols - 1)
                    bits = bits << np.uint64(1)
                    if image[yy, xx] < centre:
                        bits = bits | np.uint64(1)
            out[y, x] = bits
    return out


@njit(cache=True, nogil=True, inline="always")
def _popcount(value: np.uint64) -> int:  # pragma: no cover
    """Number of set bits (SWAR: pairs, nibbles, bytes, then a multiply)."""
    v = value - ((value >> np.uint64(1)) & np.uint64(0x5555555555555555))
    v = (v & np.uint64(0x3333333333333333)) + ((v >> np.uint64(2)) & np.uint64(0x3333333333333333))
    v = (v + (v >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return int((v * np.uint64(0x0101010101010101)) >> np.uint64(56))


@njit(cache=True, nogil=True, parallel=True)
def census_costs(
    left: np.ndarray, right: np.ndarray, d_min: int, count: int, outside: int
) -> np.ndarray:  # pragma: no cover
    """Hamming distance between left and right census signatures, per disparity (uint16)."""
    rows, cols = left.shape
    cost = np.empty((rows, cols, count), dtype=np.uint16)
    for y in prange(rows):
        for x in range(cols):
            signature = left[y, x]
            for k in range(count):
                xr = x - d_min - k
                if 0 <= xr < cols:
                    cost[y, x, k] = _popcount(signature ^ right[y, xr])
                else:
                    cost[y, x, k] = outside
    return cost


@njit(cache=True, nogil=True, parallel=True)
def box_sum(cost: np.ndarray, half: int) -> np.ndarray:  # pragma: no cover
    """Sum of each disparity's cost over the ``(2 half + 1)²`` block around each pixel,
    edge pixels repeated, in the cost's own dtype (separable: columns, then rows)."""
    rows, cols, count = cost.shape
    across = np.zeros_like(cost)
    for y in prange(rows):
        for x in range(cols):
            for dx in range(-half, half + 1):
                xx = min(max(x + dx, 0), cols - 1)
                for k in range(count):
                    across[y, x, k] += cost[y, xx, k]
    out = np.zeros_like(cost)
    for y in prange(rows):
        for dy in range(-half, half + 1):
            yy = min(max(y + dy, 0), rows - 1)
            for x in range(cols):
                for k in range(count):
                    out[y, x, k] += across[yy, x, k]
    return out


@njit(cache=True, nogil=True, fastmath=True, inline="always")
def _path_step(
    cost: np.ndarray,
    before: np.ndarray,
    before_min: float,
    out: np.ndarray,
    total: np.ndarray,
    penalty_small: float | np.number,
    penalty_large: float | np.number,
) -> float:  # pragma: no cover
    """One pixel of a path: ``out[k] = cost[k] + min(...) − before_min``, added to
    ``total``; returns min_k out. The ends of the range are done apart so that the
    inner loop has no branch (it vectorises)."""
    last = cost.size - 1
    jump = before_min + penalty_large
    if last == 0:
        value = cost[0] + min(before[0], jump) - before_min
        out[0] = value
        total[0] += value
        return value
    value = cost[0] + min(before[0], before[1] + penalty_small, jump) - before_min
    out[0] = value
    total[0] += value
    low = value
    for k in range(1, last):
        value = (
            cost[k]
            + min(before[k], before[k - 1] + penalty_small, before[k + 1] + penalty_small, jump)
            - before_min
        )
        out[k] = value
        total[k] += value
        low = min(low, value)
    value = cost[last] + min(before[last], before[last - 1] + penalty_small, jump) - before_min
    out[last] = value
    total[last] += value
    return min(low, value)


@njit(cache=True, nogil=True, fastmath=True, inline="always")
def _path_start(cost: np.ndarray, out: np.ndarray, total: np.ndarray) -> float:  # pragma: no cover
    """The first pixel of a path: ``out = cost``, added to ``total``; returns min_k."""
    low = cost[0]
    for k in range(cost.size):
        out[k] = cost[k]
        total[k] += cost[k]
        low = min(low, cost[k])
    return low


@njit(cache=True, nogil=True, fastmath=True, parallel=True)
def _aggregate_rows(
    cost: np.ndarray,
    total: np.ndarray,
    step_x: int,
    penalty_small: float | np.number,
    penalty_large: np.ndarray,
) -> None:  # pragma: no cover
    """Horizontal paths: every row is one independent path (rows in parallel)."""
    rows, cols, count = cost.shape
    for y in prange(rows):
        before = np.empty(count, dtype=cost.dtype)
        current = np.empty(count, dtype=cost.dtype)
        x = 0 if step_x > 0 else cols - 1
        before_min = _path_start(cost[y, x], before, total[y, x])
        for j in range(1, cols):
            x = j if step_x > 0 else cols - 1 - j
            before_min = _path_step(
                cost[y, x],
                before,
                before_min,
                current,
                total[y, x],
                penalty_small,
                penalty_large[y, x],
            )
            before, current = current, before


@njit(cache=True, nogil=True, fastmath=True)
def _aggregate_across_rows(
    cost: np.ndarray,
    total: np.ndarray,
    step_y: int,
    step_x: int,
    penalty_small: float | np.number,
    penalty_large: np.ndarray,
) -> None:  # pragma: no cover
    """Vertical and diagonal paths: row after row, the predecessor in the previous row."""
    rows, cols, count = cost.shape
    previous = np.empty((cols, count), dtype=cost.dtype)
    current = np.empty((cols, count), dtype=cost.dtype)
    previous_min = np.empty(cols, dtype=cost.dtype)
    current_min = np.empty(cols, dtype=cost.dtype)
    y = 0 if step_y > 0 else rows - 1
    for x in range(cols):
        previous_min[x] = _path_start(cost[y, x], previous[x], total[y, x])
    for i in range(1, rows):
        y = i if step_y > 0 else rows - 1 - i
        for x in range(cols):
            px = x - step_x
            if px < 0 or px >= cols:
                current_min[x] = _path_start(cost[y, x], current[x], total[y, x])
            else:
                current_min[x] = _path_step(
                    cost[y, x],
                    previous[px],
                    previous_min[px],
                    current[x],
                    total[y, x],
                    penalty_small,
                    penalty_large[y, x],
                )
        previous, current = current, previous
        previous_min, current_min = current_min, previous_min


def aggregate_path(
    cost: np.ndarray,
    total: np.ndarray,
    step_y: int,
    step_x: int,
    penalty_small: float | np.number,
    penalty_large: float | np.number | np.ndarray,
) -> None:
    r"""Add one path's aggregated cost to ``total`` (Hirschmüller 2008, eq. 13).

    .. math::
        L_r(p, d) = C(p, d) + \min\big(L_r(p-r, d),\ L_r(p-r, d\pm1) + P_1,\
        \min_k L_r(p-r, k) + P_2\big) - \min_k L_r(p-r, k)

    The path runs along ``r = (step_y, step_x)`` with steps in {−1, 0, 1};
    it starts afresh (``L_r = C``) where ``p − r`` leaves the image.
    """
    jumps = np.broadcast_to(np.asarray(penalty_large, dtype=cost.dtype), cost.shape[:2])
    if step_y == 0:
        _aggregate_rows(cost, total, step_x, penalty_small, jumps)
    else:
        _aggregate_across_rows(cost, total, step_y, step_x, penalty_small, jumps)


@njit(cache=True, nogil=True, parallel=True)
def winner_take_all(
    cost: np.ndarray, d_min: int, uniqueness: float, subpixel: bool
) -> np.ndarray:  # pragma: no cover
    """Disparity of least cost per pixel, NaN where it cannot be trusted.

    Only disparities whose right pixel ``x − d`` is inside the image compete.
    The winner is refused (NaN) when it lies at either end of that range (the
    true minimum may be beyond it, or the pixel not seen by the right camera
    at all: a range should hold the scene with a margin), or when a disparity
    more than one step away costs less than ``best · (1 + uniqueness)``.
    Sub-pixel: the vertex of the parabola through the minimum and its two
    neighbours.
    """
    rows, cols, count = cost.shape
    out = np.empty((rows, cols), dtype=np.float32)
    for y in prange(rows):
        for x in range(cols):
            top = min(count - 1, x - d_min)
            if top < 0:
                out[y, x] = np.nan
                continue
            best_k = 0
            best = float(cost[y, x, 0])
            for k in range(1, top + 1):
                if cost[y, x, k] < best:
                    best = float(cost[y, x, k])
                    best_k = k
            if best_k == top or best_k == 0 or not np.isfinite(best):
                out[y, x] = np.nan
                continue
            second = np.inf
            for k in range(top + 1):
                if abs(k - best_k) > 1 and cost[y, x, k] < second:
                    second = float(cost[y, x, k])
            if second < best + abs(best) * uniqueness:
                out[y, x] = np.nan
                continue
            value = np.float32(best_k)
            if subpixel:
                below = float(cost[y, x, best_k - 1])
                above = float(cost[y, x, best_k + 1])
                curvature = below - 2.0 * best + above
                if curvature > 0:
                    value += np.float32(0.5 * (below - above) / curvature)
            out[y, x] = value + d_min
    return out


@njit(cache=True, nogil=True, parallel=True)
def right_disparity(cost: np.ndarray, d_min: int) -> np.ndarray:  # pragma: no cover
    """The right image's winner-take-all disparity from the left's volume.

    Right pixel ``x_r`` at disparity ``d`` is left pixel ``x_r + d``: its cost is
    ``cost[y, x_r + d, d − d_min]`` (Hirschmüller 2008, section 3.3).
    """
    rows, cols, count = cost.shape
    out = np.empty((rows, cols), dtype=np.float32)
    for y in prange(rows):
        for xr in range(cols):
            best = np.inf
            best_d = 0
            found = False
            for k in range(count):
                x = xr + d_min + k
                if x < 0:  # a negative disparity from a pixel near the left border
                    continue
                if x >= cols:
                    break
                if cost[y, x, k] < best:
                    best = float(cost[y, x, k])
                    best_d = d_min + k
                    found = True
            out[y, xr] = np.float32(best_d) if found else np.nan
    return out


@njit(cache=True, nogil=True)
def speckle_filter(
    disparity: np.ndarray, window: int, tolerance: float
) -> np.ndarray:  # pragma: no cover
    """NaN over every 4-connected region of at most ``window`` pixels, neighbours joined
    when their disparities differ by at most ``tolerance`` (OpenCV's filterSpeckles)."""
    rows, cols = disparity.shape
    out = disparity.copy()
    done = np.zeros((rows, cols), dtype=np.bool_)
    queue = np.empty(rows * cols, dtype=np.int64)
    for start in range(rows * cols):
        y0, x0 = start // cols, start % cols
        if done[y0, x0] or not np.isfinite(disparity[y0, x0]):
            continue
        done[y0, x0] = True
        queue[0] = start
        head, tail = 0, 1
        while head < tail:
            here = queue[head]
            head += 1
            y, x = here // cols, here % cols
            value = disparity[y, x]
            for step in range(4):
                ny = y + (1 if step == 0 else -1 if step == 1 else 0)
                nx = x + (1 if step == 2 else -1 if step == 3 else 0)
                if ny < 0 or ny >= rows or nx < 0 or nx >= cols or done[ny, nx]:
                    continue
                other = disparity[ny, nx]
                if np.isfinite(other) and abs(other - value) <= tolerance:
                    done[ny, nx] = True
                    queue[tail] = ny * cols + nx
                    tail += 1
        if tail <= window:
            for i in range(tail):
                out[queue[i] // cols, queue[i] % cols] = np.nan
    return out
