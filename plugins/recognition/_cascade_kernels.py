"""numba kernels of boosted cascades (imported on first use: numba loads slowly).

One call scans every window of one scale level: for each window position the stages
run in order, each summing what its weak classifiers say about the window, and the
window is dropped at the first stage whose sum falls below the stage threshold (early
rejection), so most windows cost a few features. :func:`scan_haar_cascade` runs a
cascade of Haar-like stumps trained by ``recognition.cascade``; :func:`corner_offsets`
places an MB-LBP cascade's block corners for ``_lbp_kernels.scan_level``.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["corner_offsets", "scan_haar_cascade"]


def corner_offsets(rects: np.ndarray, feature: np.ndarray, stride: int) -> np.ndarray:
    """For each weak classifier, the flat offsets (K, 16) of its feature's 4 × 4 block
    corners in a padded integral image with rows of ``stride`` values, row-major from
    the top-left corner (relative to the window's top-left corner)."""
    x, y, w, h = (rects[feature, i][:, None] for i in range(4))
    grid = np.arange(4)[None, :]
    rows = (y + grid * h)[:, :, None]  # (K, 4, 1)
    cols = (x + grid * w)[:, None, :]  # (K, 1, 4)
    return np.ascontiguousarray((rows * stride + cols).reshape(len(feature), 16), np.int64)


@njit(cache=True, nogil=True, inline="always")
def _window_statistics(integral, squared, top, left, window_h, window_w, area, sigma_floor):
    """Mean and standard deviation (at least ``sigma_floor``) of the window at (top, left),
    from the integral images of the level and of its square (:func:`scan_haar_cascade`)."""
    b, r = top + window_h, left + window_w
    pixel_sum = integral[b, r] - integral[top, r] - integral[b, left]
    pixel_sum += integral[top, left]
    total_sq = squared[b, r] - squared[top, r] - squared[b, left]
    total_sq += squared[top, left]
    mean = pixel_sum / area
    sigma = max(np.sqrt(max(total_sq / area - mean * mean, 0.0)), sigma_floor)
    return mean, sigma


@njit(cache=True, nogil=True, inline="always")
def _haar_value(flat, base, corners, signs, t):
    """Stump ``t``'s Haar-like feature on the window at flat offset ``base``: the signed sum
    of its rectangles' sums (:func:`scan_haar_cascade`)."""
    value = 0.0
    for k in range(4):
        if signs[t, k] == 0:
            continue
        c = corners[t, k]
        part = flat[base + c[3]] - flat[base + c[1]] - flat[base + c[2]] + flat[base + c[0]]
        value += part if signs[t, k] > 0 else -part
    return value


@njit(cache=True, nogil=True)
def scan_haar_cascade(
    integral,
    squared,
    normalise,
    sigma_floor,
    window_h,
    window_w,
    step,
    corners,
    signs,
    areas,
    threshold,
    polarity,
    alpha,
    stage_end,
    stage_threshold,
):
    """The decision of a Viola–Jones cascade of Haar-like stumps on every window of one
    level, with early rejection.

    ``integral`` is the level's zero-padded integral image (float64, C order); windows
    of ``window_h`` × ``window_w`` start every ``step`` pixels, row by row. Stump t's
    feature is :math:`\\sum_k` ``signs[t, k]`` × (sum over rectangle k), rectangle k's
    corners (top-left, top-right, bottom-left, bottom-right) at the flat offsets
    ``corners[t, k]`` from the window's top-left corner; it votes ``polarity[t]`` when
    the feature exceeds ``threshold[t]``, else ``-polarity[t]``, weighted by
    ``alpha[t]``. Stage s (stumps up to ``stage_end[s]``) passes when its sum reaches
    ``stage_threshold[s]``. A window stops at its first failing stage; its decision is
    that stage's margin (below 0), or the last stage's (above 0) when it passes all,
    as ``CascadeModel.decision`` computes it. With ``normalise`` each feature is taken
    on the window scaled to zero mean and unit variance, (f − μ ``areas[t]``) / σ, μ and
    σ (at least ``sigma_floor``) from ``integral`` and ``squared``, the integral image
    of the squared level. Returns (top, left) int64 (N, 2) and the decisions (N,).
    """
    area = float(window_h * window_w)
    stride = integral.shape[1]
    flat = integral.ravel()
    tops = np.arange(0, integral.shape[0] - window_h, step)
    lefts = np.arange(0, stride - window_w, step)
    count = len(tops) * len(lefts)
    out = np.empty((count, 2), np.int64)
    decision = np.empty(count, np.float64)
    stages = stage_threshold.shape[0]
    index = 0
    for top in tops:
        for left in lefts:
            base = top * stride + left
            mean = 0.0
            sigma = 1.0
            if normalise:
                mean, sigma = _window_statistics(
                    integral, squared, top, left, window_h, window_w, area, sigma_floor
                )
            first = 0
            margin = 0.0
            for s in range(stages):
                total = 0.0
                for t in range(first, stage_end[s]):
                    value = _haar_value(flat, base, corners, signs, t)
                    if normalise:
                        value = (value - mean * areas[t]) / sigma
                    vote = polarity[t] if value > threshold[t] else -polarity[t]
                    total += vote * alpha[t]
                first = stage_end[s]
                margin = total - stage_threshold[s]
                if margin < 0:
                    break
            out[index, 0] = top
            out[index, 1] = left
            decision[index] = min(margin, -1e-12) if margin < 0 else max(margin, 1e-12)
            index += 1
    return out, decision
