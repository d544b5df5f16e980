"""numba kernel of the Gaussian pyramid (imported on first use: compiling costs time).

All the levels of one image plane in one call: each level is the previous one blurred by
symmetric taps (``mirror`` boundary, ``numpy.pad``'s ``reflect``) at its even rows and
columns only, written into one flat buffer, level after level. No padded copy and no index
arrays: the boundary is folded into the row and column numbers as they are needed.

Each value kept is computed as ``shared.separable_kernels.correlate_both`` computes it (the
column pass over the whole row into a line padded by the boundary, then the row pass at
the even positions of that line; the centre tap first, then one symmetric pair of taps at a
time, the farthest first, each ``+= weight · (far + near)``), so the levels are the same to
the bit as blurring the whole level and keeping every second row and column.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["gaussian_chain"]


@njit(cache=True, nogil=True)
def _mirror(index: int, length: int) -> int:  # pragma: no cover
    """``index`` folded into ``[0, length)`` by ``numpy.pad``'s ``reflect`` (``c b | a b c``),
    repeated for an index more than a length away (a level smaller than the taps)."""
    if length == 1:
        return 0
    period = 2 * (length - 1)
    index = index % period
    return index if index < length else period - index


@njit(cache=True, fastmath=True, nogil=True)
def _halve(
    source: np.ndarray,
    taps: np.ndarray,
    line: np.ndarray,
    even: np.ndarray,
    odd: np.ndarray,
    out: np.ndarray,
) -> None:  # pragma: no cover
    """``out`` = ``source`` blurred by ``taps`` (symmetric, odd length) at its even rows and
    columns; ``line``, ``even`` and ``odd`` are scratch of at least ``cols + 2 half``."""
    rows, cols = source.shape
    size = taps.size
    half = size // 2
    width = cols + 2 * half
    centre = line[half : half + cols]
    for r in range(out.shape[0]):
        mid = source[_mirror(2 * r, rows)]
        weight = taps[half]
        for c in range(cols):
            centre[c] = weight * mid[c]
        for j in range(half):
            far = size - 1 - j
            first = source[_mirror(2 * r + far - half, rows)]
            last = source[_mirror(2 * r + j - half, rows)]
            weight = taps[far]
            for c in range(cols):
                centre[c] += weight * (first[c] + last[c])
        for k in range(half):
            line[k] = centre[_mirror(k - half, cols)]
            line[half + cols + k] = centre[_mirror(cols + k, cols)]
        for k in range((width + 1) // 2):  # the line's even and odd positions, each contiguous
            even[k] = line[2 * k]
        for k in range(width // 2):
            odd[k] = line[2 * k + 1]
        row = out[r]
        n = row.size
        part = even[half // 2 : half // 2 + n] if half % 2 == 0 else odd[half // 2 : half // 2 + n]
        weight = taps[half]
        for c in range(n):
            row[c] = weight * part[c]
        for j in range(half):
            far = size - 1 - j
            weight = taps[far]
            first = even[far // 2 : far // 2 + n] if far % 2 == 0 else odd[far // 2 : far // 2 + n]
            last = even[j // 2 : j // 2 + n] if j % 2 == 0 else odd[j // 2 : j // 2 + n]
            for c in range(n):
                row[c] += weight * (first[c] + last[c])


@njit(cache=True, nogil=True)
def gaussian_chain(
    image: np.ndarray, taps: np.ndarray, shapes: np.ndarray, buffer: np.ndarray
) -> None:  # pragma: no cover
    """The levels after ``image``, of shapes ``shapes[1:]``, each the previous one halved,
    one after the other in ``buffer``."""
    half = taps.size // 2
    scratch = np.empty(image.shape[1] + 2 * half + 1, dtype=buffer.dtype)
    even = np.empty(scratch.size // 2 + 1, dtype=buffer.dtype)
    odd = np.empty(scratch.size // 2 + 1, dtype=buffer.dtype)
    previous = image
    start = 0
    for k in range(1, shapes.shape[0]):
        rows, cols = shapes[k, 0], shapes[k, 1]
        level = buffer[start : start + rows * cols].reshape((rows, cols))
        _halve(previous, taps, scratch, even, odd, level)
        start += rows * cols
        previous = level
