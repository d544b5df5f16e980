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
    in one pass (the running sum stays in a register across them; a SIMD loop)."""
    taps = min(weights.size - first, 5)
    w = np.zeros(5)
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
    """``out[r, c] = Σ_ij kernel[i, j] · padded[r + i, c + j]``, accumulated in float64.

    Padded row ``p`` is image row ``row_index[p]`` with columns
    ``column_index`` (−1: zero), built once into a ring of ``kh`` float64 lines;
    up to five taps of a kernel row add their shifted lines to a float64 row in
    one SIMD loop, as scipy accumulates in double, then the row is rounded once
    to float32.
    """
    rows, cols = out.shape
    kh, kw = kernel.shape
    before = kw // 2
    line = np.empty(column_index.size, dtype=np.float32)
    lines = np.zeros((kh, column_index.size + 4), dtype=np.float64)  # a ring: row p at p % kh
    total = np.empty(cols, dtype=np.float64)
    for r in range(rows):
        for p in range(0 if r == 0 else r + kh - 1, r + kh):
            fill_line(line, image, row_index[p], column_index, before)
            wide = lines[p % kh]
            for x in range(line.size):
                wide[x] = line[x]
        total[:] = 0.0
        for i in range(kh):
            for first in range(0, kw, 5):
                _add_taps(total, lines[(r + i) % kh], kernel[i], first, cols)
        row = out[r]
        for c in range(cols):
            row[c] = total[c]
