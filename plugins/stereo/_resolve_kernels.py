"""numba kernels that resolve one row of matching costs (imported on first use): each
pixel's winner take all with the uniqueness test and sub-pixel refinement, and the right
image's winners for the left-right check (see :mod:`._match_kernels`)."""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = [
    "resolve_row",
]


@njit(cache=True, nogil=True, inline="always")
def _key(cost: np.uint16, k: int) -> np.uint32:  # pragma: no cover
    """``(cost << 10) | k``: the least key is the least cost at the first disparity."""
    return np.uint32((np.uint32(cost) << np.uint32(10)) | np.uint32(k))


@njit(cache=True, nogil=True, inline="always")
def _lower(a: np.uint32, b: np.uint32) -> np.uint32:  # pragma: no cover
    """The smaller, a select on 32-bit lanes (``min`` of unsigned integers widens)."""
    return a if a < b else b


@njit(cache=True, nogil=True, inline="always")
def _least(a: np.uint16, b: np.uint16) -> np.uint16:  # pragma: no cover
    """The smaller, a select on 16-bit lanes (``min`` of unsigned integers widens)."""
    return a if a < b else b


@njit(cache=True, nogil=True)
def _winners(
    costs: np.ndarray, d_min: int, least: np.ndarray, which: np.ndarray
) -> None:  # pragma: no cover
    """``least[x]``, ``which[x]``: the first least cost of ``x`` and its ``k`` over the
    disparities whose right pixel is inside (``k ≤ x − d_min``; 65535 and 0 where none
    is): a min over the disparity rows, then the rows that reach it, last to first, each
    a select on 16-bit lanes."""
    count, cols = costs.shape
    keys = np.full(cols, 0xFFFFFFFF, dtype=np.uint32)
    for k in range(count):
        start = max(0, min(d_min + k, cols))
        row, found = costs[k, start:], keys[start:]
        for i in range(cols - start):
            found[i] = _lower(found[i], _key(row[i], k))
    for x in range(cols):
        least[x] = np.uint16(min(keys[x] >> np.uint32(10), np.uint32(0xFFFF)))
        which[x] = np.uint16(keys[x] & np.uint32(1023)) if keys[x] != np.uint32(0xFFFFFFFF) else 0


@njit(cache=True, nogil=True)
def _rivals(
    costs: np.ndarray, d_min: int, which: np.ndarray, rivals: np.ndarray
) -> None:  # pragma: no cover
    """``rivals[x]``: least cost of ``x`` more than one step from its winner (65535 when
    there is none: the caller tells that case apart), on 16-bit lanes."""
    count, cols = costs.shape
    rivals[:] = 0xFFFF
    for k in range(count):
        start = max(0, min(d_min + k, cols))
        row, winners, found = costs[k, start:], which[start:], rivals[start:]
        for i in range(cols - start):
            offset = np.uint16(np.uint16(k + 1) - winners[i])
            # |k − best| ≤ 1 (a negative offset wraps high): all ones, else none
            mask = np.uint16(np.uint16(0) - np.uint16(offset <= np.uint16(2)))
            found[i] = _least(found[i], np.uint16(row[i] | mask))


@njit(cache=True, nogil=True)
def _right_winners(costs: np.ndarray, d_min: int, out: np.ndarray) -> None:  # pragma: no cover
    """``_kernels.right_disparity`` of one row: right ``x_r`` takes the first least of
    ``costs[k, x_r + d_min + k]`` over the ``k`` that stay inside (NaN if none)."""
    count, cols = costs.shape
    keys = np.full(cols, 0xFFFFFFFF, dtype=np.uint32)
    for k in range(count):
        shift = d_min + k
        start = min(max(0, -shift), cols)
        stop = max(min(cols, cols - shift), start)
        row, found = costs[k, start + shift :], keys[start:stop]
        for i in range(stop - start):
            found[i] = _lower(found[i], _key(row[i], k))
    for xr in range(cols):
        found = keys[xr] != np.uint32(0xFFFFFFFF)
        out[xr] = np.float32(d_min + np.int64(keys[xr] & np.uint32(1023))) if found else np.nan


@njit(cache=True, nogil=True)
def resolve_row(
    costs: np.ndarray,
    d_min: int,
    uniqueness: float,
    subpixel: bool,
    out: np.ndarray,
    right_out: np.ndarray,
) -> None:  # pragma: no cover
    """One row's winners, left (``_kernels.winner_take_all``: the first least cost, refused
    at the range's ends or when a rival more than a step away is within ``uniqueness``;
    the parabola's vertex) and right, from its disparity-major costs ``(count, cols)``."""
    count, cols = costs.shape
    least = np.empty(cols, dtype=np.uint16)
    which = np.empty(cols, dtype=np.uint16)
    rivals = np.empty(cols, dtype=np.uint16)
    _winners(costs, d_min, least, which)
    _rivals(costs, d_min, which, rivals)
    for x in range(cols):
        top = min(count - 1, x - d_min)
        best_k = np.int64(which[x])
        if top < 0 or best_k == top or best_k == 0:
            out[x] = np.nan
            continue
        best = float(least[x])
        # a disparity more than one step from the winner exists (else no rival)
        second = float(rivals[x]) if best_k >= 2 or best_k + 2 <= top else np.inf
        if second < best + abs(best) * uniqueness:
            out[x] = np.nan
            continue
        value = np.float32(best_k)
        if subpixel:
            below = float(costs[best_k - 1, x])
            above = float(costs[best_k + 1, x])
            curvature = below - 2.0 * best + above
            if curvature > 0:
                value += np.float32(0.5 * (below - above) / curvature)
        out[x] = value + d_min
    _right_winners(costs, d_min, right_out)
