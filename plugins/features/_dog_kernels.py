"""numba kernels of the DoG detector: the doubled image and the keypoint search of one octave.

The search visits each inner pixel of the DoG stack once: a pixel beyond the
pre-filter is compared with its 26 neighbours (most pixels stop at the first
test, so no max or min filter of the whole stack is made), an extremum is
refined at once by the quadratic fit of Brown and Lowe, and the refined point
is kept or dropped by the contrast and edge tests. The arithmetic is the one
the vectorised numpy search did (float32 differences, float64 solve), so the
keypoints are the same up to the rounding of the 3×3 solve (about 1e-15 px).

References
----------
.. [1] D. G. Lowe, "Distinctive image features from scale-invariant keypoints",
   IJCV 60(2), 2004, sections 3 and 4.
.. [2] M. Brown, D. G. Lowe, "Invariant features from interest point groups",
   BMVC 2002.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["octave_keypoints", "upsample_twice"]


@njit(cache=True, nogil=True)
def upsample_twice(image: np.ndarray) -> np.ndarray:  # pragma: no cover
    """Bilinear doubling with pixel centres aligned (output pixel j at input j / 2 − 1/4).

    What ``scipy.ndimage.zoom(image, 2, order=1, grid_mode=True, mode="nearest")``
    computes: each output pixel weighs its two nearest input pixels per axis by
    3/4 and 1/4 (edges repeated), summed in float64.
    """
    rows, cols = image.shape
    out = np.empty((2 * rows, 2 * cols), np.float32)
    line = np.empty((2, 2 * cols), np.float64)
    for r in range(2 * rows):
        near = r // 2
        far = near - 1 if r % 2 == 0 else near + 1
        far = min(max(far, 0), rows - 1)
        for side, source in ((0, near), (1, far)):
            for c in range(2 * cols):
                nc = c // 2
                fc = nc - 1 if c % 2 == 0 else nc + 1
                fc = min(max(fc, 0), cols - 1)
                line[side, c] = 0.75 * np.float64(image[source, nc]) + 0.25 * np.float64(
                    image[source, fc]
                )
        for c in range(2 * cols):
            out[r, c] = np.float32(0.75 * line[0, c] + 0.25 * line[1, c])
    return out


@njit(cache=True, nogil=True, inline="always")
def _is_extremum(d: np.ndarray, i: int, r: int, c: int, value: np.float32, sign: int) -> bool:
    """Whether ``value`` at (i, r, c) is ≥ (sign 1) or ≤ (sign −1) all 26 neighbours."""
    for a in range(i - 1, i + 2):
        for b in range(r - 1, r + 2):
            for e in range(c - 1, c + 2):
                neighbour = d[a, b, e]
                if (neighbour > value) if sign > 0 else (neighbour < value):
                    return False
    return True


@njit(cache=True, nogil=True, inline="always")
def _row_candidates(line: np.ndarray, low: np.float32, border: int, out: np.ndarray) -> None:
    """Mark the pixels of a DoG row beyond ±``low`` and extreme beside their two row neighbours.

    A branch-free pass the compiler vectorises; the 26-neighbour test then runs
    on the few marked pixels only.
    """
    for c in range(border, line.shape[0] - border):
        v, left, right = line[c], line[c - 1], line[c + 1]
        out[c] = ((v > low) & (v >= left) & (v >= right)) | (
            (v < -low) & (v <= left) & (v <= right)
        )


@njit(cache=True, nogil=True)
def _fit(d: np.ndarray, i: int, r: int, c: int, hessian: np.ndarray, grad: np.ndarray) -> None:
    """Gradient and Hessian of the DoG at (layer i, row r, column c), float32 differences."""
    two, four = np.float32(2), np.float32(4)
    centre = d[i, r, c]
    grad[0] = (d[i, r, c + 1] - d[i, r, c - 1]) / two
    grad[1] = (d[i, r + 1, c] - d[i, r - 1, c]) / two
    grad[2] = (d[i + 1, r, c] - d[i - 1, r, c]) / two
    hessian[0, 0] = d[i, r, c + 1] + d[i, r, c - 1] - two * centre
    hessian[1, 1] = d[i, r + 1, c] + d[i, r - 1, c] - two * centre
    hessian[2, 2] = d[i + 1, r, c] + d[i - 1, r, c] - two * centre
    hessian[0, 1] = hessian[1, 0] = (
        d[i, r + 1, c + 1] - d[i, r + 1, c - 1] - d[i, r - 1, c + 1] + d[i, r - 1, c - 1]
    ) / four
    hessian[0, 2] = hessian[2, 0] = (
        d[i + 1, r, c + 1] - d[i + 1, r, c - 1] - d[i - 1, r, c + 1] + d[i - 1, r, c - 1]
    ) / four
    hessian[1, 2] = hessian[2, 1] = (
        d[i + 1, r + 1, c] - d[i + 1, r - 1, c] - d[i - 1, r + 1, c] + d[i - 1, r - 1, c]
    ) / four


@njit(cache=True, nogil=True)
def _solve3(a: np.ndarray, b: np.ndarray, x: np.ndarray) -> float:
    """x = a⁻¹ b by Gaussian elimination with partial pivoting; returns det(a); overwrites a, b."""
    det = 1.0
    for k in range(3):
        p = k
        for i in range(k + 1, 3):
            if abs(a[i, k]) > abs(a[p, k]):
                p = i
        if p != k:
            det = -det
            for j in range(3):
                a[k, j], a[p, j] = a[p, j], a[k, j]
            b[k], b[p] = b[p], b[k]
        det *= a[k, k]
        if a[k, k] == 0.0:
            return 0.0
        for i in range(k + 1, 3):
            factor = a[i, k] / a[k, k]
            for j in range(k, 3):
                a[i, j] -= factor * a[k, j]
            b[i] -= factor * b[k]
    for k in range(2, -1, -1):
        total = b[k]
        for j in range(k + 1, 3):
            total -= a[k, j] * x[j]
        x[k] = total / a[k, k]
    return det


@njit(cache=True, nogil=True)
def _refine(d, i, r, c, intervals, border, offset, grad):  # pragma: no cover
    """Up to five quadratic fits, moving to the nearest pixel while an offset exceeds 1/2.

    Returns the final (layer, row, column), or layer −1 for an unstable point
    (singular Hessian, moved out of the inner layers or border, or not settled).
    """
    hessian = np.empty((3, 3), np.float64)
    rhs = np.empty(3, np.float64)
    rows, cols = d.shape[1], d.shape[2]
    for _ in range(5):
        _fit(d, i, r, c, hessian, grad)
        for k in range(3):
            rhs[k] = -grad[k]
        if abs(_solve3(hessian, rhs, offset)) <= 1e-12:
            return -1, r, c
        if abs(offset[0]) < 0.5 and abs(offset[1]) < 0.5 and abs(offset[2]) < 0.5:
            return i, r, c
        c += int(round(offset[0]))
        r += int(round(offset[1]))
        i += int(round(offset[2]))
        if i < 1 or i > intervals or r < border or r >= rows - border:
            return -1, r, c
        if c < border or c >= cols - border:
            return -1, r, c
    return -1, r, c


@njit(cache=True, nogil=True)
def _keep(d, i, r, c, offset, grad, threshold, edge_ratio):  # pragma: no cover
    """|D| at the refined point if it passes the contrast and edge tests, else −1."""
    two, four = np.float32(2), np.float32(4)
    value = np.float64(d[i, r, c]) + 0.5 * (
        grad[0] * offset[0] + grad[1] * offset[1] + grad[2] * offset[2]
    )
    dxx = d[i, r, c + 1] + d[i, r, c - 1] - two * d[i, r, c]
    dyy = d[i, r + 1, c] + d[i, r - 1, c] - two * d[i, r, c]
    dxy = (d[i, r + 1, c + 1] - d[i, r + 1, c - 1] - d[i, r - 1, c + 1] + d[i, r - 1, c - 1]) / four
    trace, det = dxx + dyy, dxx * dyy - dxy * dxy
    ratio = np.float32(edge_ratio)
    bound = np.float32((edge_ratio + 1.0) ** 2)
    if abs(value) >= threshold and det > 0 and trace * trace * ratio < bound * det:
        return abs(value)
    return -1.0


@njit(cache=True, nogil=True)
def octave_keypoints(dog, prefilter, threshold, edge_ratio, intervals, border):  # pragma: no cover
    """Refined DoG extrema of one octave's stack ``dog`` (intervals + 2, H, W), float32.

    Rows of (layer, x, y, |D|), fractional, in the order of the pixels found
    (layer, then row, then column). ``prefilter`` and ``threshold`` are the
    pre-filter (compared in float32) and the contrast threshold on |D|.
    """
    rows, cols = dog.shape[1], dog.shape[2]
    low = np.float32(prefilter)
    out = np.empty((64, 4), np.float64)
    found = 0
    offset = np.empty(3, np.float64)
    grad = np.empty(3, np.float64)
    hopeful = np.zeros(cols, np.bool_)
    for i in range(1, intervals + 1):
        for r in range(border, rows - border):
            _row_candidates(dog[i, r], low, border, hopeful)
            for c in range(border, cols - border):
                if not hopeful[c]:
                    continue
                value = dog[i, r, c]
                sign = 1 if value > 0 else -1
                if not _is_extremum(dog, i, r, c, value, sign):
                    continue
                layer, y, x = _refine(dog, i, r, c, intervals, border, offset, grad)
                if layer < 0:
                    continue
                response = _keep(dog, layer, y, x, offset, grad, threshold, edge_ratio)
                if response < 0:
                    continue
                if found == out.shape[0]:
                    grown = np.empty((2 * found, 4), np.float64)
                    grown[:found] = out
                    out = grown
                out[found, 0] = layer + offset[2]
                out[found, 1] = x + offset[0]
                out[found, 2] = y + offset[1]
                out[found, 3] = response
                found += 1
    return out[:found]
