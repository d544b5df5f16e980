"""numba kernel of 2-D correlation with any kernel (imported on first use: compiling costs time)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ._padded_rows import fill_line

__all__ = ["correlate_2d"]


@njit(cache=True, fastmath=True, nogil=True)
def _add_taps(
    total: np.ndarray, line: np.ndarray, weights: np.ndarray, first: int, cols: int
) -> None:  # pragma: no cover
    """``total[c] += Σ weights[first + t] · line[c + first + t]`` for up to five taps ``t``
    in one pass, in float32 (the running sum stays in a register across them; a SIMD loop)."""
    taps = min(weights.size - first, 5)
    w = np.zeros(5, dtype=np.float32)
    w[:taps] = weights[first : first + taps]
    a, b, c, d, e = (
        line[first:],
        line[first + 1 :],
        line[first + 2 :],
        line[first + 3 :],
        line[first + 4 :],
    )
    w0, w1, w2, w3, w4 = w[0], w[1], w[2], w[3], w[4]
    if taps == 5:
        for x in range(cols):
            total[x] += w0 * a[x] + w1 * b[x] + w2 * c[x] + w3 * d[x] + w4 * e[x]
    elif taps == 4:
        for x in range(cols):
            total[x] += w0 * a[x] + w1 * b[x] + w2 * c[x] + w3 * d[x]
    elif taps == 3:
        for x in range(cols):
            total[x] += w0 * a[x] + w1 * b[x] + w2 * c[x]
    elif taps == 2:
        for x in range(cols):
            total[x] += w0 * a[x] + w1 * b[x]
    else:
        for x in range(cols):
            total[x] += w0 * a[x]


@njit(cache=True, fastmath=True, nogil=True)
def correlate_2d(
    image: np.ndarray,
    kernel: np.ndarray,
    row_index: np.ndarray,
    column_index: np.ndarray,
    out: np.ndarray,
) -> None:  # pragma: no cover
    """``out[r, c] = Σ_ij kernel[i, j] · padded[r + i, c + j]``, accumulated in float32.

    Padded row ``p`` is image row ``row_index[p]`` with columns
    ``column_index`` (−1: zero), built once into a ring of ``kh`` float32 lines;
    up to five taps of a kernel row add their shifted lines to the output row in
    one SIMD loop (eight float32 lanes), as OpenCV's ``filter2D`` accumulates in
    float32. Against float64 accumulation (scipy), an output differs by at most
    about ``(kh·⌈kw/5⌉ + 5) · 2⁻²⁴ · Σ|kernel| · max|image|`` (each addition
    rounds once, relative to the running sum, itself bounded by that sum).
    """
    rows, cols = out.shape
    kh, kw = kernel.shape
    before = kw // 2
    width = column_index.size
    lines = np.zeros((kh, width + 4), dtype=np.float32)  # a ring: row p at p % kh
    for r in range(rows):
        for p in range(0 if r == 0 else r + kh - 1, r + kh):
            fill_line(lines[p % kh, :width], image, row_index[p], column_index, before)
        total = out[r]
        total[:] = 0.0
        for i in range(kh):
            for first in range(0, kw, 5):
                _add_taps(total, lines[(r + i) % kh], kernel[i], first, cols)
