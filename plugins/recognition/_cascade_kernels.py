"""numba kernels of boosted cascades (imported on first use: numba loads slowly).

One call scans every window of one scale level: for each window position the stages
run in order, each summing what its weak classifiers say about the window, and the
window is dropped at the first stage whose sum falls below the stage threshold (early
rejection), so most windows cost a few features. :func:`scan_windows` runs a cascade
of MB-LBP stumps read from OpenCV's format, :func:`scan_haar_cascade` a cascade of
Haar-like stumps trained by ``recognition.cascade``.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["TIE", "corner_offsets", "scan_haar_cascade", "scan_windows"]

TIE = 1e-6
"""Block sums closer than this are equal (an MB-LBP bit is 1 when a neighbour's sum
reaches the centre's). OpenCV sums integers, so its ties are exact; float sums of the
same blocks differ by rounding (about 1e-10 at 512 × 512), far below one gray level
over one pixel (1/255)."""


def corner_offsets(rects: np.ndarray, feature: np.ndarray, stride: int) -> np.ndarray:
    """For each weak classifier, the flat offsets (K, 16) of its feature's 4 × 4 block
    corners in a padded integral image with rows of ``stride`` values, row-major from
    the top-left corner (relative to the window's top-left corner)."""
    x, y, w, h = (rects[feature, i][:, None] for i in range(4))
    grid = np.arange(4)[None, :]
    rows = (y + grid * h)[:, :, None]  # (K, 4, 1)
    cols = (x + grid * w)[:, None, :]  # (K, 1, 4)
    return np.ascontiguousarray((rows * stride + cols).reshape(len(feature), 16), np.int64)


@numba.njit(cache=True, nogil=True, inline="always")
def _code(flat, base, off):
    """The 8-bit MB-LBP code of the 3 × 3 blocks whose 16 corners (row-major) are
    ``flat[base + off]`` in a flat integral image: bit 7 (top-left block) to bit 0
    (middle-left), clockwise, set where the block's sum reaches the centre block's
    (OpenCV's order)."""
    c0, c1, c2, c3 = (
        flat[base + off[0]],
        flat[base + off[1]],
        flat[base + off[2]],
        flat[base + off[3]],
    )
    c4, c5, c6, c7 = (
        flat[base + off[4]],
        flat[base + off[5]],
        flat[base + off[6]],
        flat[base + off[7]],
    )
    c8, c9, c10, c11 = (
        flat[base + off[8]],
        flat[base + off[9]],
        flat[base + off[10]],
        flat[base + off[11]],
    )
    c12, c13, c14, c15 = (
        flat[base + off[12]],
        flat[base + off[13]],
        flat[base + off[14]],
        flat[base + off[15]],
    )
    centre = c10 - c6 - c9 + c5 - TIE
    code = 0
    if c5 - c1 - c4 + c0 >= centre:
        code |= 128
    if c6 - c2 - c5 + c1 >= centre:
        code |= 64
    if c7 - c3 - c6 + c2 >= centre:
        code |= 32
    if c11 - c7 - c10 + c6 >= centre:
        code |= 16
    if c15 - c11 - c14 + c10 >= centre:
        code |= 8
    if c14 - c10 - c13 + c9 >= centre:
        code |= 4
    if c13 - c9 - c12 + c8 >= centre:
        code |= 2
    if c9 - c5 - c8 + c4 >= centre:
        code |= 1
    return code


@numba.njit(cache=True, nogil=True)
def scan_windows(
    integral, window_h, window_w, step, offsets, subsets, leaves, stage_end, thresholds
):
    """Windows of one level that pass every stage.

    ``integral`` is the level's zero-padded integral image (float64, C order); windows
    of ``window_h`` × ``window_w`` start every ``step`` pixels. Weak classifier k reads
    its feature's 16 block corners at ``offsets[k]`` (:func:`corner_offsets`), goes to
    ``leaves[k, 0]`` when bit ``code`` of ``subsets[k]`` (8 uint32 words) is set and to
    ``leaves[k, 1]`` otherwise; stage s owns the weak classifiers up to ``stage_end[s]``
    and passes when its sum reaches ``thresholds[s]``. Returns the windows' (top, left)
    int64 (N, 2), the last stage's sum minus its threshold (N,), and the number of weak
    classifiers evaluated.
    """
    stride = integral.shape[1]
    flat = integral.ravel()
    rows = integral.shape[0] - 1 - window_h
    cols = stride - 1 - window_w
    tops = []
    lefts = []
    margins = []
    evaluated = 0
    stages = thresholds.shape[0]
    for top in range(0, rows + 1, step):
        for left in range(0, cols + 1, step):
            base = top * stride + left
            first = 0
            margin = 0.0
            for s in range(stages):
                total = 0.0
                for k in range(first, stage_end[s]):
                    code = _code(flat, base, offsets[k])
                    if (subsets[k, code >> 5] >> (code & 31)) & 1:
                        total += leaves[k, 0]
                    else:
                        total += leaves[k, 1]
                evaluated += stage_end[s] - first
                first = stage_end[s]
                margin = total - thresholds[s]
                if margin < 0:
                    break
            if margin >= 0:
                tops.append(top)
                lefts.append(left)
                margins.append(margin)
    out = np.empty((len(tops), 2), np.int64)
    score = np.empty(len(tops), np.float64)
    for i in range(len(tops)):
        out[i, 0] = tops[i]
        out[i, 1] = lefts[i]
        score[i] = margins[i]
    return out, score, evaluated


@numba.njit(cache=True, nogil=True)
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
                b, r = top + window_h, left + window_w
                pixel_sum = integral[b, r] - integral[top, r] - integral[b, left]
                pixel_sum += integral[top, left]
                total_sq = squared[b, r] - squared[top, r] - squared[b, left]
                total_sq += squared[top, left]
                mean = pixel_sum / area
                sigma = max(np.sqrt(max(total_sq / area - mean * mean, 0.0)), sigma_floor)
            first = 0
            margin = 0.0
            for s in range(stages):
                total = 0.0
                for t in range(first, stage_end[s]):
                    value = 0.0
                    for k in range(4):
                        if signs[t, k] == 0:
                            continue
                        c = corners[t, k]
                        part = (
                            flat[base + c[3]]
                            - flat[base + c[1]]
                            - flat[base + c[2]]
                            + flat[base + c[0]]
                        )
                        value += part if signs[t, k] > 0 else -part
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
