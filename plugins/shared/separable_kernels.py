"""numba kernels of the separable filter core (imported on first use: compiling costs time).

Taps that are symmetric (:math:`h(-u) = h(u)`, a Gaussian, a box) or
antisymmetric (:math:`h(-u) = -h(u)`, a derivative) are applied in pairs, as
scipy's ``correlate1d`` does,

.. math:: g(i) = h(0)\\, f(i) + \\sum_{u>0} h(u)\\,[f(i + u) \\pm f(i - u)],

which halves the multiplications and makes a derivative of a constant
exactly zero (:math:`f(i + u) - f(i - u) = 0` in any precision).

The passes compute in the output's dtype: a ``float32`` image filtered into a ``float64``
``out`` has every sample widened (exactly) where the column pass reads it, the same
values to the bit as filtering ``image.astype(np.float64)``, without that copy.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numba.extending import overload

from .jit import njit

__all__ = ["correlate_both", "correlate_both_halved"]


def _in_dtype_of(value: Any, like: np.ndarray) -> Any:
    """``value`` converted to the dtype of the array ``like`` (exactly, when it widens):
    the compiled form is :func:`_in_dtype_of_compiled`'s, a no-op when the dtypes agree."""
    return like.dtype.type(value)


@overload(_in_dtype_of, inline="always")
def _in_dtype_of_compiled(value: Any, like: Any) -> Callable[[Any, Any], Any]:
    """numba's typing of :func:`_in_dtype_of`: a cast to ``like``'s element type."""
    target = like.dtype

    def convert(value: Any, like: Any) -> Any:  # pragma: no cover
        return target(value)

    return convert


@njit(cache=True, fastmath=True, nogil=True)
def _accumulate(
    out: np.ndarray, first: np.ndarray, last: np.ndarray, weight: float, symmetry: int
) -> None:  # pragma: no cover
    """``out += weight · (first ± last)``, ``symmetry`` 1 (+) or −1 (−); 0: ``weight · first``,
    each sample of ``first`` and ``last`` in ``out``'s dtype first."""
    if symmetry == 1:
        for c in range(out.size):
            out[c] += weight * (_in_dtype_of(first[c], out) + _in_dtype_of(last[c], out))
    elif symmetry == -1:
        for c in range(out.size):
            out[c] += weight * (_in_dtype_of(first[c], out) - _in_dtype_of(last[c], out))
    else:
        for c in range(out.size):
            out[c] += weight * _in_dtype_of(first[c], out)


@njit(cache=True, fastmath=True, nogil=True)
def _pass(
    out: np.ndarray,
    lines: np.ndarray,
    index: np.ndarray,
    start: int,
    taps: np.ndarray,
    symmetry: int,
    zero: np.ndarray,
) -> None:  # pragma: no cover
    """``out = Σ_j taps[j] · lines[index[start + j]]`` (``index`` −1: the line ``zero``, of
    the lines' dtype), in ``out``'s dtype."""
    size = taps.size
    half = size // 2
    centre = index[start + half]
    if symmetry == 0:
        out[:] = 0.0
        for j in range(size):
            line = lines[index[start + j]] if index[start + j] >= 0 else zero
            _accumulate(out, line, line, taps[j], 0)
        return
    if centre >= 0:
        source = lines[centre]
        for c in range(out.size):
            out[c] = taps[half] * _in_dtype_of(source[c], out)
    else:
        out[:] = 0.0
    for j in range(half):
        far = size - 1 - j
        first = lines[index[start + far]] if index[start + far] >= 0 else zero
        last = lines[index[start + j]] if index[start + j] >= 0 else zero
        _accumulate(out, first, last, taps[far], symmetry)


@njit(cache=True, fastmath=True, nogil=True)
def correlate_both(
    image: np.ndarray,
    column_taps: np.ndarray,
    column_symmetry: int,
    row_index: np.ndarray,
    row_taps: np.ndarray,
    row_symmetry: int,
    column_index: np.ndarray,
    out: np.ndarray,
) -> None:  # pragma: no cover
    """Correlate down the columns then along the rows, one output row at a time.

    ``row_index[r + j]`` is the image row under tap ``j`` of output row ``r``
    (the boundary rule, −1 for zero) and ``column_index`` the same along a
    row, so no padded copy of the image is made: each output row is the
    column pass into a small padded line, its ends filled by ``column_index``,
    then the row pass over that line, both while the rows are in cache.
    """
    rows, cols = out.shape
    size = row_taps.size
    half = size // 2
    line = np.zeros(cols + 2 * half, out.dtype)
    zero = np.zeros(cols, image.dtype)  # the rows outside the image under "constant"
    for r in range(rows):
        centre = line[half : half + cols]
        _pass(centre, image, row_index, r, column_taps, column_symmetry, zero)
        for k in range(half):
            left, right = column_index[k], column_index[half + cols + k]
            line[k] = centre[left] if left >= 0 else 0.0
            line[half + cols + k] = centre[right] if right >= 0 else 0.0
        row = out[r]
        if row_symmetry == 0:
            row[:] = 0.0
            for j in range(size):
                _accumulate(row, line[j : j + cols], line[j : j + cols], row_taps[j], 0)
            continue
        for c in range(cols):
            row[c] = row_taps[half] * centre[c]
        for j in range(half):
            far = size - 1 - j
            _accumulate(
                row, line[far : far + cols], line[j : j + cols], row_taps[far], row_symmetry
            )


@njit(cache=True, fastmath=True, nogil=True)
def correlate_both_halved(
    image: np.ndarray,
    column_taps: np.ndarray,
    column_symmetry: int,
    row_index: np.ndarray,
    row_taps: np.ndarray,
    row_symmetry: int,
    column_index: np.ndarray,
    out: np.ndarray,
) -> None:  # pragma: no cover
    """:func:`correlate_both` at the even rows and columns only (``out`` is half the size).

    Each value kept is computed as :func:`correlate_both` computes it (the column pass
    over the whole padded line, the row pass's terms in the same order), the rows and
    columns a halving drops are not computed at all.
    """
    cols = image.shape[1]
    size = row_taps.size
    half = size // 2
    line = np.zeros(cols + 2 * half, out.dtype)
    even = np.empty((line.size + 1) // 2, out.dtype)
    odd = np.empty(line.size // 2, out.dtype)
    zero = np.zeros(cols, image.dtype)
    for r in range(out.shape[0]):
        centre = line[half : half + cols]
        _pass(centre, image, row_index, 2 * r, column_taps, column_symmetry, zero)
        for k in range(half):
            left, right = column_index[k], column_index[half + cols + k]
            line[k] = centre[left] if left >= 0 else 0.0
            line[half + cols + k] = centre[right] if right >= 0 else 0.0
        for k in range(line.size):  # the line's even and odd positions, each contiguous
            if k % 2 == 0:
                even[k // 2] = line[k]
            else:
                odd[k // 2] = line[k]
        row = out[r]
        n = row.size
        if row_symmetry == 0:
            row[:] = 0.0
            for j in range(size):
                part = even[j // 2 : j // 2 + n] if j % 2 == 0 else odd[j // 2 : j // 2 + n]
                for c in range(n):
                    row[c] += row_taps[j] * part[c]
            continue
        mid = even[half // 2 : half // 2 + n] if half % 2 == 0 else odd[half // 2 : half // 2 + n]
        for c in range(n):
            row[c] = row_taps[half] * mid[c]
        for j in range(half):
            far = size - 1 - j
            weight = row_taps[far]
            first = even[far // 2 : far // 2 + n] if far % 2 == 0 else odd[far // 2 : far // 2 + n]
            last = even[j // 2 : j // 2 + n] if j % 2 == 0 else odd[j // 2 : j // 2 + n]
            if row_symmetry == 1:
                for c in range(n):
                    row[c] += weight * (first[c] + last[c])
            else:
                for c in range(n):
                    row[c] += weight * (first[c] - last[c])
