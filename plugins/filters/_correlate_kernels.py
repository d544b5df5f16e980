"""numba kernel of 2-D correlation with any kernel (imported on first use: compiling costs time)."""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit
from ._padded_rows import fill_line

__all__ = ["correlate_2d"]


@njit(cache=True, fastmath=True, nogil=True)
def _add_taps(
    total: np.ndarray, line: np.ndarray, weights: np.ndarray, first: int, cols: int, keep: bool
) -> None:  # pragma: no cover
    """``total[c] += Σ weights[first + t] · line[c + first + t]`` for up to five taps ``t``
    in one pass, in float32 (the running sum stays in a register across them; a SIMD loop);
    ``keep`` False: ``total[c] =`` instead (the first pass of a row, no zeroing pass)."""
    taps = min(weights.size - first, 5)
    zero = np.float32(0.0)  # scalars, not a small array allocated per call (per row)
    w0 = np.float32(weights[first])
    w1 = np.float32(weights[first + 1]) if taps > 1 else zero
    w2 = np.float32(weights[first + 2]) if taps > 2 else zero
    w3 = np.float32(weights[first + 3]) if taps > 3 else zero
    w4 = np.float32(weights[first + 4]) if taps > 4 else zero
    a, b, c, d, e = (
        line[first:],
        line[first + 1 :],
        line[first + 2 :],
        line[first + 3 :],
        line[first + 4 :],
    )
    if taps == 5:
        for x in range(cols):
            total[x] = (w0 * a[x] + w1 * b[x] + w2 * c[x] + w3 * d[x] + w4 * e[x]) + (
                total[x] if keep else zero
            )
    elif taps == 4:
        for x in range(cols):
            total[x] = (w0 * a[x] + w1 * b[x] + w2 * c[x] + w3 * d[x]) + (
                total[x] if keep else zero
            )
    elif taps == 3:
        for x in range(cols):
            total[x] = (w0 * a[x] + w1 * b[x] + w2 * c[x]) + (total[x] if keep else zero)
    elif taps == 2:
        for x in range(cols):
            total[x] = (w0 * a[x] + w1 * b[x]) + (total[x] if keep else zero)
    else:
        for x in range(cols):
            total[x] = (w0 * a[x]) + (total[x] if keep else zero)


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
        for i in range(kh):
            for first in range(0, kw, 5):
                _add_taps(total, lines[(r + i) % kh], kernel[i], first, cols, i + first > 0)
