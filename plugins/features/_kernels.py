"""numba kernels of SIFT's orientation and descriptor (imported on first use: numba loads slowly).

Both are histograms of the gradients around a keypoint in its pyramid level.
The gradient (central differences, magnitude and ``atan2`` angle) is computed
on demand, for the pixels some keypoint's window reaches, and kept in the
level's ``magnitude`` / ``angle`` arrays with a ``done`` flag: a level's
keypoints cover a fraction of it, and ``atan2`` of every pixel of every level
was the largest single cost of SIFT. The values are the whole-image ones
(float32 ``hypot`` and ``atan2`` of the C library; numpy's own AVX-512 ``arctan2``,
where the machine has it, differs from the C library's in the last bit for some values).

The descriptor is a scatter of every pixel of a rotated window into 8
trilinearly interpolated histogram bins; in numpy that is a ``bincount``
over eight times the window's pixels, in a compiled loop it is a few
floating-point operations per pixel (about ten times faster, measured in
``bench/bench_homography.py``).
"""

from __future__ import annotations

import math

import numpy as np

from ..shared.jit import njit

__all__ = ["descriptor_histograms", "orientation_histograms"]


@njit(cache=True, nogil=True, inline="always")
def _gradient(image, magnitude, angle, done, y, x):  # pragma: no cover
    """Fill the gradient of inner pixel (y, x) of ``image`` if not yet computed."""
    if not done[y, x]:
        dx = image[y, x + 1] - image[y, x - 1]
        dy = image[y + 1, x] - image[y - 1, x]
        magnitude[y, x] = math.hypot(dx, dy)
        angle[y, x] = math.atan2(dy, dx)
        done[y, x] = True


@njit(cache=True, nogil=True)
def orientation_histograms(image, magnitude, angle, done, cx, cy, sigma, bins):  # pragma: no cover
    r"""Smoothed orientation histograms (Lowe 2004, section 5) of keypoints in one level.

    The pixels within ``round(3σ)`` of the keypoint's rounded position vote
    their magnitude times :math:`e^{-d^2 / 2\sigma^2}` into ``bins`` bins; the
    histogram is then smoothed by (1, 4, 6, 4, 1) / 16, circularly.
    """
    rows, cols = image.shape
    out = np.zeros((cx.shape[0], bins), np.float64)
    hist = np.zeros(bins, np.float64)
    count, two_pi = np.float32(bins), np.float32(2.0 * math.pi)
    for k in range(cx.shape[0]):
        hist[:] = 0.0
        radius = int(round(3.0 * sigma[k]))
        x0, y0 = int(round(cx[k])), int(round(cy[k]))
        spread = 2.0 * sigma[k] ** 2
        gauss = np.empty(radius * radius + 1, np.float64)  # by squared distance
        for d2 in range(radius * radius + 1):
            gauss[d2] = math.exp(-d2 / spread)
        for dy in range(-radius, radius + 1):
            y = y0 + dy
            if y <= 0 or y >= rows - 1:
                continue
            for dx in range(-radius, radius + 1):
                x = x0 + dx
                if x <= 0 or x >= cols - 1 or dx * dx + dy * dy > radius * radius:
                    continue
                _gradient(image, magnitude, angle, done, y, x)
                weight = gauss[dx * dx + dy * dy] * magnitude[y, x]
                hist[int(math.floor(angle[y, x] * count / two_pi)) % bins] += weight
        for b in range(bins):
            left, right = hist[b - 1], hist[(b + 1) % bins]
            out[k, b] = (hist[b - 2] + hist[(b + 2) % bins] + 4 * (left + right) + 6 * hist[b]) / 16
    return out


@njit(cache=True, nogil=True, inline="always")
def _vote(hist, rbin, cbin, obin, weight):  # pragma: no cover
    """Trilinear vote of ``weight`` at fractional (row, column, orientation) bin."""
    r0, c0, o0 = int(math.floor(rbin)), int(math.floor(cbin)), int(math.floor(obin))
    fr, fc, fo = rbin - r0, cbin - c0, obin - o0
    for dr in range(2):
        wr = weight * (fr if dr else 1.0 - fr)
        for dc in range(2):
            wrc = wr * (fc if dc else 1.0 - fc)
            hist[r0 + 1 + dr, c0 + 1 + dc, o0] += wrc * (1.0 - fo)
            hist[r0 + 1 + dr, c0 + 1 + dc, o0 + 1] += wrc * fo


@njit(cache=True, nogil=True, inline="always")
def _row_span(cos_t, sin_t, oy, reach, cx):  # pragma: no cover
    r"""Columns (a pixel wider each side) of one row that can fall in the rotated window.

    The window is :math:`|c\,o_x + s\,o_y| < R` and :math:`|-s\,o_x + c\,o_y| < R`
    (:math:`R` = ``reach``); each slab bounds :math:`o_x` when its coefficient is
    not zero. The caller still tests every pixel: the span only skips those that
    surely fail.
    """
    low, high = -math.inf, math.inf
    if abs(cos_t) > 1e-9:
        a, b = (-reach - sin_t * oy) / cos_t, (reach - sin_t * oy) / cos_t
        low, high = max(low, min(a, b)), min(high, max(a, b))
    if abs(sin_t) > 1e-9:
        a, b = (cos_t * oy - reach) / sin_t, (cos_t * oy + reach) / sin_t
        low, high = max(low, min(a, b)), min(high, max(a, b))
    if low > high:
        return 1, 0
    return int(math.floor(low + cx)) - 1, int(math.ceil(high + cx)) + 1


@njit(cache=True, nogil=True)
def _describe(hist, image, magnitude, angle, done, cx, cy, w, theta, cells, bins):
    r"""Accumulate one keypoint's raw histogram into ``hist`` (cells + 2, cells + 2, bins + 2).

    The Gaussian weight :math:`e^{-(x_r^2 + y_r^2) / 2 (d/2)^2}` of the rotated
    coordinates in cell widths equals :math:`e^{-o_x^2 / s}\, e^{-o_y^2 / s}`,
    :math:`s = 2 (d w / 2)^2`, the offsets' (a rotation keeps lengths), so it
    is two tables of exponentials per keypoint instead of one per pixel.
    """
    rows, cols = magnitude.shape
    two_pi = 2.0 * math.pi
    half = 0.5 * cells
    cos_t, sin_t, inverse = math.cos(theta), math.sin(theta), 1.0 / w
    radius = int(round(w * math.sqrt(2.0) * (cells + 1) * 0.5))
    radius = min(radius, int(math.sqrt(rows * rows + cols * cols)))
    x0, y0 = int(round(cx)), int(round(cy))
    spread = -1.0 / (2.0 * half * half * w * w)
    along_x = np.empty(2 * radius + 1, np.float64)
    for d in range(-radius, radius + 1):
        along_x[d + radius] = math.exp(spread * (x0 + d - cx) ** 2)
    for dy in range(-radius, radius + 1):
        y = y0 + dy
        if y <= 0 or y >= rows - 1:
            continue
        oy = y - cy
        along_y = math.exp(spread * oy * oy)
        first, last = _row_span(cos_t, sin_t, oy, (half + 0.5) * w, cx)
        first, last = max(x0 - radius, first, 1), min(x0 + radius, last, cols - 2)
        for x in range(first, last + 1):
            dx = x - x0
            ox = x - cx
            rbin = (-sin_t * ox + cos_t * oy) * inverse + half - 0.5
            cbin = (cos_t * ox + sin_t * oy) * inverse + half - 0.5
            if rbin <= -1.0 or rbin >= cells or cbin <= -1.0 or cbin >= cells:
                continue
            _gradient(image, magnitude, angle, done, y, x)
            relative = angle[y, x] - theta
            while relative < 0.0:
                relative += two_pi
            while relative >= two_pi:
                relative -= two_pi
            weight = along_y * along_x[dx + radius] * magnitude[y, x]
            _vote(hist, rbin, cbin, relative * (bins / two_pi), weight)


@njit(cache=True, nogil=True)
def descriptor_histograms(image, magnitude, angle, done, cx, cy, width, theta, cells, bins):
    """Raw (cells × cells × bins) histograms for keypoints at (cx, cy) in one pyramid level.

    ``width`` is the cell width (3σ) and ``theta`` the orientation of each keypoint.
    """
    count = cx.shape[0]
    out = np.zeros((count, cells * cells * bins), np.float32)
    hist = np.zeros((cells + 2, cells + 2, bins + 2), np.float64)
    for k in range(count):
        hist[:] = 0.0
        _describe(
            hist, image, magnitude, angle, done, cx[k], cy[k], width[k], theta[k], cells, bins
        )
        for r in range(cells):
            for c in range(cells):
                for o in range(bins):
                    value = hist[r + 1, c + 1, o]
                    if o == 0:
                        value += hist[r + 1, c + 1, bins]  # orientation bins wrap around
                    out[k, (r * cells + c) * bins + o] = value
    return out
