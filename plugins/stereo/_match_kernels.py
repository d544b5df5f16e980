"""numba kernels of census matching, row by row (imported on first use: compiling costs time).

Block matching never builds the cost volume: each row's census costs go into a ring of
the last ``block + 1`` rows, a running sum over the ring gives each column's sum over
the block's rows (one addition and one subtraction per cost, whatever the block), a
running sum along the row gives the block sums, and the row is resolved at once
(winner take all and the right image's winners). Semi-global matching fills its volume
the same way, then aggregates its paths in two sweeps, the four paths that come from
above and from the left in a forward sweep, the other four in a backward one, each
pixel's predecessors kept in row buffers; each row is resolved as soon as the backward
sweep has finished it. All sums are integers (census bits), so the results are those of
``_kernels.py``'s volume kernels to the bit; ``cost_volume`` documents the layout.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import types
from numba.extending import intrinsic

from ..shared.jit import njit
from ._resolve_kernels import resolve_row

__all__ = [
    "census_block_match",
    "census_signatures",
    "census_volume",
    "jump_penalties",
]


@intrinsic
def _ctpop(typingctx: Any, value: Any) -> Any:  # pragma: no cover
    """The set bits of a uint64 (LLVM's ctpop: one POPCNT instruction)."""
    signature = types.uint64(types.uint64)

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        return builder.ctpop(args[0])

    return signature, codegen


@njit(cache=True, nogil=True)
def census_signatures(image: np.ndarray, half: int) -> np.ndarray:  # pragma: no cover
    """Census signatures as ``_kernels.census`` makes them (a bit per window pixel darker
    than the centre, edge pixels repeated, row-major window order), a row at a time."""
    rows, cols = image.shape
    padded = np.empty((rows + 2 * half, cols + 2 * half), dtype=image.dtype)
    for y in range(rows + 2 * half):
        source = min(max(y - half, 0), rows - 1)
        for x in range(cols + 2 * half):
            padded[y, x] = image[source, min(max(x - half, 0), cols - 1)]
    out = np.zeros((rows, cols), dtype=np.uint64)
    for y in range(rows):
        bits = out[y]
        centre = padded[y + half, half : half + cols]
        for dy in range(2 * half + 1):
            for dx in range(2 * half + 1):
                if dy == half and dx == half:
                    continue
                other = padded[y + dy, dx : dx + cols]
                for x in range(cols):
                    bits[x] = (bits[x] << np.uint64(1)) | np.uint64(other[x] < centre[x])
    return out


@njit(cache=True, nogil=True)
def _cost_row(
    left: np.ndarray, right: np.ndarray, d_min: int, outside: int, out: np.ndarray
) -> None:  # pragma: no cover
    """``out[k, x]``: Hamming distance of left ``x`` and right ``x − d_min − k`` (``outside``
    where that leaves the image); disparity-major, so each disparity is one vector loop."""
    count, cols = out.shape
    for k in range(count):
        shift, row = d_min + k, out[k]
        start = min(max(shift, 0), cols)
        stop = max(min(cols + shift, cols), start)
        # loops from 0 over slices: a signed index from elsewhere keeps numba's
        # negative-index check in the loop, and then it does not vectorise
        row[:start] = outside
        row[stop:] = outside
        inside, lefts, rights = row[start:stop], left[start:stop], right[start - shift :]
        for i in range(stop - start):
            inside[i] = _ctpop(lefts[i] ^ rights[i])  # type: ignore[call-arg]


@njit(cache=True, nogil=True)
def _block_rows(
    left: np.ndarray, right: np.ndarray, d_min: int, count: int, outside: int, half: int
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """Row pipeline state: the ring of cost rows and the column sums of row 0."""
    rows, cols = left.shape
    ring = np.empty((2 * half + 2, count, cols), dtype=np.uint16)
    for source in range(min(half + 1, rows)):
        _cost_row(left[source], right[source], d_min, outside, ring[source % ring.shape[0]])
    columns = np.zeros((count, cols), dtype=np.uint16)
    for dy in range(-half, half + 1):
        source = ring[min(max(dy, 0), rows - 1) % ring.shape[0]]
        for k in range(count):
            for x in range(cols):
                columns[k, x] += source[k, x]
    return ring, columns


@njit(cache=True, nogil=True)
def _next_columns(
    left: np.ndarray,
    right: np.ndarray,
    d_min: int,
    outside: int,
    half: int,
    y: int,
    ring: np.ndarray,
    columns: np.ndarray,
) -> None:  # pragma: no cover
    """Column sums of row ``y − 1`` → row ``y``: add the entering row, drop the leaving one
    (modulo 2¹⁶: every sum fits)."""
    rows = left.shape[0]
    entering, leaving = min(y + half, rows - 1), max(y - half - 1, 0)
    size = ring.shape[0]
    if y + half <= rows - 1:
        _cost_row(left[entering], right[entering], d_min, outside, ring[entering % size])
    new, old = ring[entering % size].reshape(-1), ring[leaving % size].reshape(-1)
    flat = columns.reshape(-1)
    for i in range(flat.size):
        flat[i] = np.uint16(np.uint16(flat[i] + new[i]) - old[i])


@njit(cache=True, nogil=True, inline="always")
def _clamped_sum(row: np.ndarray, x: int, half: int) -> np.uint16:  # pragma: no cover
    """``Σ row[clamp(x + dx)]`` over ``|dx| ≤ half`` (an end of the row)."""
    total = np.uint16(0)
    cols = row.size
    for dx in range(-half, half + 1):
        total = np.uint16(total + row[min(max(x + dx, 0), cols - 1)])
    return total


@njit(cache=True, nogil=True, inline="always")
def _add_shifted(
    middle: np.ndarray, row: np.ndarray, first: int, taps: int, start: bool
) -> None:  # pragma: no cover
    """``middle[i] (= 0 when start) + Σ row[i + first + t]`` over ``t < taps ≤ 5``, one
    SIMD pass (the partial sum stays in a register across the taps; modulo 2¹⁶)."""
    n = middle.size
    a, b, c = row[first:], row[first + 1 :], row[first + 2 :]
    d, e = row[first + 3 :], row[first + 4 :]
    if taps == 5:
        if start:
            for i in range(n):
                middle[i] = np.uint16(a[i] + b[i] + c[i] + d[i] + e[i])
        else:
            for i in range(n):
                middle[i] = np.uint16(middle[i] + a[i] + b[i] + c[i] + d[i] + e[i])
    elif taps == 4:
        if start:
            for i in range(n):
                middle[i] = np.uint16(a[i] + b[i] + c[i] + d[i])
        else:
            for i in range(n):
                middle[i] = np.uint16(middle[i] + a[i] + b[i] + c[i] + d[i])
    elif taps == 3:
        if start:
            for i in range(n):
                middle[i] = np.uint16(a[i] + b[i] + c[i])
        else:
            for i in range(n):
                middle[i] = np.uint16(middle[i] + a[i] + b[i] + c[i])
    elif taps == 2:
        if start:
            for i in range(n):
                middle[i] = np.uint16(a[i] + b[i])
        else:
            for i in range(n):
                middle[i] = np.uint16(middle[i] + a[i] + b[i])
    elif start:
        middle[:] = a[:n]
    else:
        for i in range(n):
            middle[i] = np.uint16(middle[i] + a[i])


@njit(cache=True, nogil=True)
def _across(columns: np.ndarray, half: int, out: np.ndarray) -> None:  # pragma: no cover
    """``out[k, x] = Σ columns[k, clamp(x + dx)]`` over ``|dx| ≤ half``: inside, up to five
    shifted rows summed in one SIMD pass (two passes for a block of 9, not eight
    read-modify-write passes); the clamped ends apart."""
    count, cols = columns.shape
    inner = max(cols - half, half)
    width = 2 * half + 1
    for k in range(count):
        row, sums = columns[k], out[k]
        middle = sums[half:inner]
        for first in range(0, width, 5):
            _add_shifted(middle, row, first, min(width - first, 5), first == 0)
        for x in range(min(half, cols)):
            sums[x] = _clamped_sum(row, x, half)
        for x in range(inner, cols):
            sums[x] = _clamped_sum(row, x, half)


@njit(cache=True, nogil=True)
def census_block_match(
    left: np.ndarray,
    right: np.ndarray,
    d_min: int,
    count: int,
    outside: int,
    half: int,
    uniqueness: float,
    subpixel: bool,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """Left and right winner-take-all disparities of census signatures ``left``, ``right``,
    costs summed over ``(2 half + 1)²`` blocks (edge pixels repeated), without a volume."""
    rows, cols = left.shape
    out = np.empty((rows, cols), dtype=np.float32)
    right_out = np.empty((rows, cols), dtype=np.float32)
    ring, columns = _block_rows(left, right, d_min, count, outside, half)
    summed = np.empty((count, cols), dtype=np.uint16)
    for y in range(rows):
        if y > 0:
            _next_columns(left, right, d_min, outside, half, y, ring, columns)
        _across(columns, half, summed)
        resolve_row(summed, d_min, uniqueness, subpixel, out[y], right_out[y])
    return out, right_out


@njit(cache=True, nogil=True)
def census_volume(
    left: np.ndarray, right: np.ndarray, d_min: int, count: int, outside: int, half: int
) -> np.ndarray:  # pragma: no cover
    """The census cost volume summed over ``(2 half + 1)²`` blocks, uint16, disparity-major
    ``(rows, count, cols)`` (``box_sum(census_costs(...), half)`` with its last two axes
    swapped, by running sums)."""
    rows, cols = left.shape
    volume = np.empty((rows, count, cols), dtype=np.uint16)
    ring, columns = _block_rows(left, right, d_min, count, outside, half)
    for y in range(rows):
        if y > 0:
            _next_columns(left, right, d_min, outside, half, y, ring, columns)
        _across(columns, half, volume[y])
    return volume


@njit(cache=True, nogil=True)
def jump_penalties(
    image: np.ndarray, steps: np.ndarray, p1: float, p2: float, edge: float
) -> np.ndarray:  # pragma: no cover
    """``uint16(max(P1, P2 / (1 + |I(p) − I(p − r)| / edge)))`` per path ``r`` of ``steps``,
    edge pixels repeated, computed in float64 as ``_disparity._jumps`` does (edge ≤ 0:
    P2 everywhere)."""
    rows, cols = image.shape
    out = np.empty((steps.shape[0], rows, cols), dtype=np.uint16)
    for i in range(steps.shape[0]):
        step_y, step_x = steps[i, 0], steps[i, 1]
        for y in range(rows):
            yb = min(max(y - step_y, 0), rows - 1)
            for x in range(cols):
                if edge <= 0:
                    out[i, y, x] = np.uint16(p2)
                    continue
                xb = min(max(x - step_x, 0), cols - 1)
                change = abs(np.float64(image[y, x]) - np.float64(image[yb, xb]))
                out[i, y, x] = np.uint16(max(p1, p2 / (1.0 + change / edge)))
    return out


@njit(cache=True, nogil=True)
def left_right_keep(
    disparity: np.ndarray, right_disparity: np.ndarray, tolerance: float
) -> np.ndarray:  # pragma: no cover
    """``_disparity.left_right_check`` pixel by pixel: a left pixel is kept when the right
    pixel at ``x − ⌊d⌋`` or at ``x − ⌈d⌉`` (inside the image) holds a disparity within
    ``tolerance`` of ``⌊d⌋`` (resp. ``⌈d⌉``); NaN otherwise."""
    rows, cols = disparity.shape
    out = np.empty((rows, cols), dtype=np.float32)
    for y in range(rows):
        for x in range(cols):
            value = disparity[y, x]
            keep = False
            if np.isfinite(value):
                for whole in (np.floor(value), np.ceil(value)):
                    xr = x - np.int64(whole)
                    if 0 <= xr < cols:
                        keep |= bool(np.float32(abs(whole - right_disparity[y, xr])) <= tolerance)
            out[y, x] = value if keep else np.nan
    return out
