"""numba kernels of the separable filter core (imported on first use: compiling costs time)."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["correlate_columns", "correlate_rows"]


@njit(cache=True, fastmath=True, nogil=True)
def correlate_columns(
    padded: np.ndarray, taps: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover
    """``out[r, c] = Σ_j taps[j] · padded[r + j, c]``: whole rows at a time (SIMD inner loop)."""
    rows, cols = out.shape
    for r in range(rows):
        for c in range(cols):
            out[r, c] = 0.0
        for j in range(taps.size):
            weight = taps[j]
            for c in range(cols):
                out[r, c] += weight * padded[r + j, c]


@njit(cache=True, fastmath=True, nogil=True)
def correlate_rows(
    padded: np.ndarray, taps: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover
    """``out[r, c] = Σ_j taps[j] · padded[r, c + j]``: one row at a time, taps outer."""
    rows, cols = out.shape
    for r in range(rows):
        for c in range(cols):
            out[r, c] = 0.0
        for j in range(taps.size):
            weight = taps[j]
            for c in range(cols):
                out[r, c] += weight * padded[r, c + j]
