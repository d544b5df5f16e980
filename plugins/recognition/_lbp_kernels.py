"""numba kernels of the MB-LBP cascade (imported on first use: numba loads slowly).

:func:`resample_integral` builds one scale's integral image from the input's (the exact
integral of the area-averaged image, see ``_lbp_cascade``); :func:`scan_level` runs the
cascade over every window of that level, stage by stage, dropping a window at the first
stage it fails (early rejection), so most windows cost the first stage's few features.
"""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["TIE", "padded_integral", "resample_integral", "scan_level"]

TIE = 1e-6
"""Block sums closer than this are equal (an MB-LBP bit is 1 when a neighbour's sum
reaches the centre's). OpenCV sums integers, so its ties are exact; float sums of the
same blocks differ by rounding (about 1e-10 at 512 × 512), far below one gray level
over one pixel (1/255)."""


@njit(cache=True, nogil=True)
def padded_integral(image):
    """The zero-padded integral image of a 2-D image, float64 (H + 1, W + 1): the
    sum of the pixels above and left of each corner, summed down the columns first and
    then along the rows (NumPy's ``cumsum(axis=0).cumsum(axis=1)``, the same roundings)."""
    height, width = image.shape
    out = np.zeros((height + 1, width + 1))
    column = np.zeros(width)
    for r in range(height):
        running = 0.0
        for c in range(width):
            column[c] += image[r, c]
            running += column[c]
            out[r + 1, c + 1] = running
    return out


@njit(cache=True, nogil=True)
def resample_integral(padded, scale):
    r"""The zero-padded integral image of the image reduced by ``scale``:
    :math:`S_s(v, u) = F(v s, u s)`, F the padded integral ``padded`` interpolated
    bilinearly (exact for a piecewise-constant image), float64
    (⌊H / s⌋ + 1, ⌊W / s⌋ + 1)."""
    height, width = padded.shape[0] - 1, padded.shape[1] - 1
    rows = int(height / scale + 1e-9) + 1
    cols = int(width / scale + 1e-9) + 1
    c0 = np.empty(cols, np.intp)
    fc = np.empty(cols)
    for u in range(cols):
        x = min(u * scale, width)
        c0[u] = min(int(np.floor(x)), width - 1)
        fc[u] = x - c0[u]
    out = np.empty((rows, cols))
    for v in range(rows):
        y = min(v * scale, height)
        r0 = min(int(np.floor(y)), height - 1)
        fr = y - r0
        for u in range(cols):
            a, f = c0[u], fc[u]
            top = padded[r0, a] * (1 - f) + padded[r0, a + 1] * f
            bottom = padded[r0 + 1, a] * (1 - f) + padded[r0 + 1, a + 1] * f
            out[v, u] = top * (1 - fr) + bottom * fr
    return out


@njit(cache=True, nogil=True, inline="always")
def _code(flat, base, off, k):
    """The 8-bit MB-LBP code of weak classifier k's 3 × 3 blocks, whose 16 corners
    (row-major) are ``flat[base + off[k]]``: bit 7 (top-left block) to bit 0
    (middle-left), clockwise, set where the block's sum reaches the centre block's
    (OpenCV's order)."""
    c0, c1, c2, c3 = (
        flat[base + off[k, 0]],
        flat[base + off[k, 1]],
        flat[base + off[k, 2]],
        flat[base + off[k, 3]],
    )
    c4, c5, c6, c7 = (
        flat[base + off[k, 4]],
        flat[base + off[k, 5]],
        flat[base + off[k, 6]],
        flat[base + off[k, 7]],
    )
    c8, c9, c10, c11 = (
        flat[base + off[k, 8]],
        flat[base + off[k, 9]],
        flat[base + off[k, 10]],
        flat[base + off[k, 11]],
    )
    c12, c13, c14, c15 = (
        flat[base + off[k, 12]],
        flat[base + off[k, 13]],
        flat[base + off[k, 14]],
        flat[base + off[k, 15]],
    )
    centre = c10 - c6 - c9 + c5 - TIE
    return (
        (int(c5 - c1 - c4 + c0 >= centre) << 7)
        | (int(c6 - c2 - c5 + c1 >= centre) << 6)
        | (int(c7 - c3 - c6 + c2 >= centre) << 5)
        | (int(c11 - c7 - c10 + c6 >= centre) << 4)
        | (int(c15 - c11 - c14 + c10 >= centre) << 3)
        | (int(c14 - c10 - c13 + c9 >= centre) << 2)
        | (int(c13 - c9 - c12 + c8 >= centre) << 1)
        | int(c9 - c5 - c8 + c4 >= centre)
    )


@njit(cache=True, nogil=True)
def scan_level(integral, window_h, window_w, step, offsets, subsets, leaves, stage_end, thresholds):
    """Windows of one level that pass every stage.

    ``integral`` is the level's zero-padded integral image (float64, C order); windows
    of ``window_h`` × ``window_w`` start every ``step`` pixels. Weak classifier k reads
    its feature's 16 block corners at the flat offsets ``offsets[k]`` (from the window's
    top-left corner), goes to ``leaves[k, 0]`` when bit ``code`` of ``subsets[k]`` (8
    uint32 words) is set and to ``leaves[k, 1]`` otherwise; stage s owns the weak
    classifiers up to ``stage_end[s]`` and passes when its sum reaches
    ``thresholds[s]``. Returns the windows' (top, left) int64 (N, 2), the last stage's
    sum minus its threshold (N,), and the number of weak classifiers evaluated.
    """
    stride = integral.shape[1]
    flat = integral.ravel()
    rows = integral.shape[0] - 1 - window_h
    cols = stride - 1 - window_w
    stages = thresholds.shape[0]
    capacity = 64
    out = np.empty((capacity, 2), np.int64)
    score = np.empty(capacity)
    found = 0
    evaluated = 0
    for top in range(0, rows + 1, step):
        for left in range(0, cols + 1, step):
            base = top * stride + left
            k = 0
            margin = 0.0
            for s in range(stages):
                total = 0.0
                end = stage_end[s]
                evaluated += end - k
                while k < end:
                    code = _code(flat, base, offsets, k)
                    if (subsets[k, code >> 5] >> (code & 31)) & 1:
                        total += leaves[k, 0]
                    else:
                        total += leaves[k, 1]
                    k += 1
                margin = total - thresholds[s]
                if margin < 0:
                    break
            if margin >= 0:
                if found == capacity:
                    capacity *= 2
                    out = _grown(out, capacity)
                    score = _grown(score, capacity)
                out[found, 0] = top
                out[found, 1] = left
                score[found] = margin
                found += 1
    return out[:found].copy(), score[:found].copy(), evaluated


@njit(cache=True, nogil=True)
def _grown(array, capacity):
    """``array`` copied into a new one of ``capacity`` rows."""
    bigger = np.empty((capacity, *array.shape[1:]), array.dtype)
    bigger[: len(array)] = array
    return bigger
