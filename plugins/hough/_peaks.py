"""Peaks of an accumulator: local maxima, a threshold, greedy suppression, sub-bin refinement."""

from __future__ import annotations

import numpy as np

__all__ = ["local_maxima", "parabolic_offset", "quadratic_peak_2d", "suppress_close"]


def local_maxima(accumulator: np.ndarray, size: int, floor: float) -> np.ndarray:
    """Indices (rows of an ``N×ndim`` array) of cells that are the maximum of their window.

    A cell counts when it equals the maximum of its ``size``-wide window and
    exceeds ``floor`` (strictly, so an empty accumulator has no peak).
    """
    import scipy.ndimage as ndi

    window_max = ndi.maximum_filter(accumulator, size=size, mode="nearest")
    return np.argwhere((accumulator == window_max) & (accumulator > floor))


def parabolic_offset(left: np.ndarray, centre: np.ndarray, right: np.ndarray) -> np.ndarray:
    r"""Sub-bin offset of a peak from three samples: the vertex of the fitted parabola.

    .. math:: \delta = \frac{l - r}{2\,(l - 2c + r)} \in [-\tfrac12, \tfrac12]
    """
    curvature = left - 2.0 * centre + right
    safe = np.where(curvature < 0, curvature, -1.0)
    return np.where(curvature < 0, np.clip((left - right) / (2.0 * safe), -0.5, 0.5), 0.0)


def quadratic_peak_2d(array: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    r"""Sub-cell offsets ``(N, 2)`` of 2-D peaks: the vertex of a quadratic fitted to each 3×3.

    .. math:: f(u, v) = a + b u + c v + d u^2 + e v^2 + g u v, \qquad
              \begin{bmatrix} 2d & g \\ g & 2e \end{bmatrix}
              \begin{bmatrix} u \\ v \end{bmatrix} = -\begin{bmatrix} b \\ c \end{bmatrix}

    The cross term matters where a ridge runs obliquely through the cells
    (a line's peak in (θ, ρ)); separate 1-D parabolas would be biased there.
    Peaks must not touch the array's border. Offsets are clipped to ±½ and
    fall back to the 1-D parabolas where the fit is not a maximum.
    """
    u = np.repeat([-1.0, 0.0, 1.0], 3)  # row offsets, in the order of the patches below
    v = np.tile([-1.0, 0.0, 1.0], 3)
    design = np.column_stack([np.ones(9), u, v, u * u, v * v, u * v])
    solve = np.linalg.pinv(design)  # (6, 9)
    patches = np.stack(
        [array[rows + du, cols + dv] for du in (-1, 0, 1) for dv in (-1, 0, 1)], axis=1
    )
    _, b, c, d, e, g = solve @ patches.T
    det = 4.0 * d * e - g * g
    maximum = (d < 0) & (det > 0)
    safe = np.where(maximum, det, 1.0)
    du = np.where(maximum, (-2.0 * e * b + g * c) / safe, 0.0)
    dv = np.where(maximum, (-2.0 * d * c + g * b) / safe, 0.0)
    centre = array[rows, cols]
    fallback_u = parabolic_offset(array[rows - 1, cols], centre, array[rows + 1, cols])
    fallback_v = parabolic_offset(array[rows, cols - 1], centre, array[rows, cols + 1])
    good = maximum & (np.abs(du) <= 1) & (np.abs(dv) <= 1)
    offsets = np.column_stack([np.where(good, du, fallback_u), np.where(good, dv, fallback_v)])
    return np.clip(offsets, -0.5, 0.5)


def suppress_close(
    positions: np.ndarray, scores: np.ndarray, min_distance: float, limit: int
) -> np.ndarray:
    """Greedy non-maximum suppression: indices of peaks, strongest first, kept at least
    ``min_distance`` apart (Euclidean over the columns of ``positions``), at most ``limit``."""
    from ._circle_kernels import greedy_suppression

    order = np.argsort(-scores, kind="stable")
    points = np.ascontiguousarray(positions, dtype=np.float64)
    if points.ndim == 1:  # one coordinate per peak
        points = points.reshape(-1, 1)
    return greedy_suppression(points, order, float(min_distance), int(limit))
