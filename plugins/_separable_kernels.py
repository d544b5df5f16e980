"""numba kernels of the separable filter core (imported on first use: compiling costs time).

Taps that are symmetric (:math:`h(-u) = h(u)`, a Gaussian, a box) or
antisymmetric (:math:`h(-u) = -h(u)`, a derivative) are applied in pairs, as
scipy's ``correlate1d`` does,

.. math:: g(i) = h(0)\\, f(i) + \\sum_{u>0} h(u)\\,[f(i + u) \\pm f(i - u)],

which halves the multiplications and makes a derivative of a constant
exactly zero (:math:`f(i + u) - f(i - u) = 0` in any precision).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["ANTISYMMETRIC", "GENERAL", "SYMMETRIC", "correlate_columns", "correlate_rows"]

GENERAL, SYMMETRIC, ANTISYMMETRIC = 0, 1, -1


@njit(cache=True, fastmath=True, nogil=True)
def _accumulate(
    out: np.ndarray, first: np.ndarray, last: np.ndarray, weight: float, symmetry: int
) -> None:  # pragma: no cover
    """``out += weight · (first ± last)`` (or ``weight · first`` when general), a SIMD loop."""
    if symmetry == 1:
        for c in range(out.size):
            out[c] += weight * (first[c] + last[c])
    elif symmetry == -1:
        for c in range(out.size):
            out[c] += weight * (first[c] - last[c])
    else:
        for c in range(out.size):
            out[c] += weight * first[c]


@njit(cache=True, fastmath=True, nogil=True)
def correlate_columns(
    padded: np.ndarray, taps: np.ndarray, out: np.ndarray, symmetry: int
) -> None:  # pragma: no cover
    """``out[r, c] = Σ_j taps[j] · padded[r + j, c]``: whole rows at a time (SIMD inner loop)."""
    rows, cols = out.shape
    size = taps.size
    half = size // 2
    for r in range(rows):
        row = out[r]
        if symmetry == 0:
            row[:] = 0.0
            for j in range(size):
                _accumulate(row, padded[r + j], padded[r + j], taps[j], 0)
        else:
            centre = padded[r + half]
            for c in range(cols):
                row[c] = taps[half] * centre[c]
            for j in range(half):
                _accumulate(
                    row, padded[r + size - 1 - j], padded[r + j], taps[size - 1 - j], symmetry
                )


@njit(cache=True, fastmath=True, nogil=True)
def correlate_rows(
    padded: np.ndarray, taps: np.ndarray, out: np.ndarray, symmetry: int
) -> None:  # pragma: no cover
    """``out[r, c] = Σ_j taps[j] · padded[r, c + j]``: one row at a time, taps outer."""
    rows, cols = out.shape
    size = taps.size
    half = size // 2
    for r in range(rows):
        row, source = out[r], padded[r]
        if symmetry == 0:
            row[:] = 0.0
            for j in range(size):
                _accumulate(row, source[j : j + cols], source[j : j + cols], taps[j], 0)
        else:
            for c in range(cols):
                row[c] = taps[half] * source[c + half]
            for j in range(half):
                far = size - 1 - j
                _accumulate(
                    row, source[far : far + cols], source[j : j + cols], taps[far], symmetry
                )
