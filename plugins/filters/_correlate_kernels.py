"""numba kernel of 2-D correlation with any kernel (imported on first use: compiling costs time)."""

from __future__ import annotations

import numpy as np
from numba import njit

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


@njit(cache=True, nogil=True, inline="always")
def _weights5(weights: np.ndarray, first: int) -> tuple:  # pragma: no cover
    """Taps ``first … first + 4`` of a kernel row as float32 scalars (zero past its end)."""
    taps = min(weights.size - first, 5)
    zero = np.float32(0.0)
    return (
        np.float32(weights[first]),
        np.float32(weights[first + 1]) if taps > 1 else zero,
        np.float32(weights[first + 2]) if taps > 2 else zero,
        np.float32(weights[first + 3]) if taps > 3 else zero,
        np.float32(weights[first + 4]) if taps > 4 else zero,
    )


@njit(cache=True, fastmath=True, nogil=True, inline="always")
def _dot5(w: tuple, line: np.ndarray, x: int) -> np.float32:  # pragma: no cover
    """``Σ_t w[t] · line[x + t]``, the five products of :func:`_add_taps` in its order."""
    return (
        w[0] * line[x]
        + w[1] * line[x + 1]
        + w[2] * line[x + 2]
        + w[3] * line[x + 3]
        + (w[4] * line[x + 4])
    )


@njit(cache=True, fastmath=True, nogil=True)
def _add_rows(
    total: np.ndarray, lines: tuple, weights: tuple, cols: int, keep: bool
) -> None:  # pragma: no cover
    """:func:`_add_taps` of up to five taps of three kernel rows in one pass: the same sums
    in the same order (row by row onto the running total), which stays in a register
    instead of being stored and reloaded between rows."""
    zero = np.float32(0.0)
    a, b, c = lines
    wa, wb, wc = weights
    for x in range(cols):
        running = _dot5(wa, a, x) + (total[x] if keep else zero)
        running = _dot5(wb, b, x) + running
        total[x] = _dot5(wc, c, x) + running


@njit(cache=True, fastmath=True, nogil=True)
def _add_five_rows(
    total: np.ndarray, lines: tuple, weights: tuple, cols: int, keep: bool
) -> None:  # pragma: no cover
    """:func:`_add_rows` for five kernel rows."""
    zero = np.float32(0.0)
    a, b, c, d, e = lines
    wa, wb, wc, wd, we = weights
    for x in range(cols):
        running = _dot5(wa, a, x) + (total[x] if keep else zero)
        running = _dot5(wb, b, x) + running
        running = _dot5(wc, c, x) + running
        running = _dot5(wd, d, x) + running
        total[x] = _dot5(we, e, x) + running


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
        for first in range(0, kw, 5):
            _add_row_taps(total, lines, kernel, r, first, cols)


@njit(cache=True, fastmath=True, nogil=True)
def _add_row_taps(
    total: np.ndarray, lines: np.ndarray, kernel: np.ndarray, r: int, first: int, cols: int
) -> None:  # pragma: no cover
    """Taps ``first … first + 4`` of every kernel row onto output row ``r``: five rows a
    pass while five remain, then three, then one (``lines`` the ring of padded rows)."""
    kh = kernel.shape[0]
    i = 0
    while i < kh:
        keep = i + first > 0
        if kh - i >= 5:
            rows = (
                lines[(r + i) % kh, first:],
                lines[(r + i + 1) % kh, first:],
                lines[(r + i + 2) % kh, first:],
                lines[(r + i + 3) % kh, first:],
                lines[(r + i + 4) % kh, first:],
            )
            weights = (
                _weights5(kernel[i], first),
                _weights5(kernel[i + 1], first),
                _weights5(kernel[i + 2], first),
                _weights5(kernel[i + 3], first),
                _weights5(kernel[i + 4], first),
            )
            _add_five_rows(total, rows, weights, cols, keep)
            i += 5
        elif kh - i >= 3:
            three = (
                lines[(r + i) % kh, first:],
                lines[(r + i + 1) % kh, first:],
                lines[(r + i + 2) % kh, first:],
            )
            taps = (
                _weights5(kernel[i], first),
                _weights5(kernel[i + 1], first),
                _weights5(kernel[i + 2], first),
            )
            _add_rows(total, three, taps, cols, keep)
            i += 3
        else:
            _add_taps(total, lines[(r + i) % kh], kernel[i], first, cols, keep)
            i += 1
