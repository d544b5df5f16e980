"""numba kernel of the homography's RANSAC loop (imported on first use: numba loads slowly).

:func:`ransac_homography` runs :func:`~graphvision_plugins.fitting.ransac`'s loop compiled
for 4-point samples: the samples of ``Generator.choice`` (:mod:`..fitting._kernels`),
:func:`._homography.estimate_homography`'s normalised DLT with its degeneracy tests, and
:func:`._homography.transfer_error`'s inliers, with the same arithmetic; in Python each
sample paid NumPy's per-call overhead on 4-row arrays a dozen times.
"""

from __future__ import annotations

import math

import numpy as np

from ..fitting._kernels import draw_sample, iterations_needed
from ..shared.jit import njit

__all__ = ["ransac_homography"]


@njit(cache=True, nogil=True)
def _normalised(points):  # pragma: no cover - compiled
    """(T points, T) with T of :func:`._homography.normalising_transform`."""
    n = points.shape[0]
    cx = points[:, 0].sum() / n
    cy = points[:, 1].sum() / n
    spread = 0.0
    for i in range(n):
        spread += (points[i, 0] - cx) ** 2 + (points[i, 1] - cy) ** 2
    spread = math.sqrt(spread / n)
    scale = math.sqrt(2.0) / spread if spread > 0 else 1.0
    out = np.empty((n, 2))
    for i in range(n):
        out[i, 0] = scale * points[i, 0] + -scale * cx
        out[i, 1] = scale * points[i, 1] + -scale * cy
    return out, scale, cx, cy


@njit(cache=True, nogil=True)
def _collinear_triple(p):  # pragma: no cover - compiled
    for i, j, k in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)):
        u0, u1 = p[j, 0] - p[i, 0], p[j, 1] - p[i, 1]
        v0, v1 = p[k, 0] - p[i, 0], p[k, 1] - p[i, 1]
        if abs(u0 * v1 - u1 * v0) < 1e-6:
            return True
    return False


@njit(cache=True, nogil=True)
def dlt(src, dst):  # pragma: no cover - compiled
    """(H, True) through 4 or more correspondences, (zeros, False) where
    :func:`._homography.estimate_homography` returns None."""
    n = src.shape[0]
    if n < 4 or not (np.isfinite(src).all() and np.isfinite(dst).all()):
        return np.zeros((3, 3)), False
    a, sa, cax, cay = _normalised(src)
    b, sb, cbx, cby = _normalised(dst)
    if n == 4 and (_collinear_triple(a) or _collinear_triple(b)):
        return np.zeros((3, 3)), False
    rows = np.zeros((2 * n, 9))
    for i in range(n):
        x = (a[i, 0], a[i, 1], 1.0)
        for j in range(3):
            rows[2 * i, j] = -x[j]
            rows[2 * i, 6 + j] = b[i, 0] * x[j]
            rows[2 * i + 1, 3 + j] = -x[j]
            rows[2 * i + 1, 6 + j] = b[i, 1] * x[j]
    _, singular, vt = np.linalg.svd(rows, full_matrices=2 * n < 9)
    if singular[singular.shape[0] - 2] < 1e-10 * singular[0]:
        return np.zeros((3, 3)), False
    h = vt[8].copy().reshape(3, 3)
    t_src = np.array([[sa, 0.0, -sa * cax], [0.0, sa, -sa * cay], [0.0, 0.0, 1.0]])
    t_dst_inv = np.array([[1.0 / sb, 0.0, cbx], [0.0, 1.0 / sb, cby], [0.0, 0.0, 1.0]])
    h = t_dst_inv @ h @ t_src
    if abs(h[2, 2]) < 1e-12 or not np.isfinite(h).all():
        return np.zeros((3, 3)), False
    return h / h[2, 2], True


@njit(cache=True, nogil=True)
def transfer_inliers(h, src, dst, threshold, out):  # pragma: no cover - compiled
    """``out[i]`` = forward transfer error of match i below ``threshold``; their count."""
    found = 0
    for i in range(src.shape[0]):
        x, y = src[i, 0], src[i, 1]
        w = x * h[2, 0] + y * h[2, 1] + h[2, 2]
        dx = (x * h[0, 0] + y * h[0, 1] + h[0, 2]) / w - dst[i, 0]
        dy = (x * h[1, 0] + y * h[1, 1] + h[1, 2]) / w - dst[i, 1]
        inside = math.sqrt(dx * dx + dy * dy) < threshold  # NaN and inf are outside
        out[i] = inside
        found += inside
    return found


@njit(cache=True, nogil=True)
def ransac_homography(src, dst, threshold, confidence, max_iterations, rng):  # pragma: no cover
    """(best H, its inlier mask, samples drawn, whether any sample gave a model)."""
    count = src.shape[0]
    best, best_inliers, best_count = np.zeros((3, 3)), np.zeros(count, np.bool_), -1
    inliers = np.zeros(count, np.bool_)
    sample = np.empty(4, np.int64)
    needed, drawn = max_iterations, 0
    while drawn < min(needed, max_iterations):
        drawn += 1
        draw_sample(rng, count, sample)
        h, ok = dlt(src[sample], dst[sample])
        if not ok:
            continue
        found = transfer_inliers(h, src, dst, threshold, inliers)
        if found > best_count:
            best, best_count = h, found
            best_inliers[:] = inliers
            needed = iterations_needed(1.0 - found / count, 4, confidence)
    return best, best_inliers, drawn, best_count >= 0
