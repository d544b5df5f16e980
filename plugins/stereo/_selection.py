"""From a cost volume to a disparity map: the volume summed over blocks, winner take all
with uniqueness and sub-pixel refinement, the left-right check and the speckle filter."""

from __future__ import annotations

import numpy as np

from ._cost import Cost, cost_volume
from ._speckles import speckles

__all__ = [
    "left_right_check",
]


def left_right_check(
    disparity: np.ndarray, right_disparity: np.ndarray, tolerance: float
) -> np.ndarray:
    r"""NaN where the right image's disparity disagrees with the left's by more than
    ``tolerance`` pixels (occlusions and mismatches; Hirschmüller 2008, section 3.3).

    A sub-pixel disparity :math:`d` points between the right pixels
    :math:`x - \lfloor d \rfloor` and :math:`x - \lceil d \rceil`; the left pixel is
    kept when either of them that lies inside the image holds a disparity within
    ``tolerance`` of :math:`\lfloor d \rfloor` (resp. :math:`\lceil d \rceil`), as
    OpenCV's StereoSGBM checks (``disp12MaxDiff``). Comparing :math:`d` with the
    right pixel nearest to :math:`x - d` instead refuses correct pixels of
    slanted surfaces whose disparity lies half-way between two integers.
    """
    from ._match_kernels import left_right_keep

    kept: np.ndarray = left_right_keep(
        np.ascontiguousarray(disparity, np.float32),
        np.ascontiguousarray(right_disparity, np.float32),
        float(tolerance),
    )
    return kept


def _select(
    volume: np.ndarray,
    d_min: int,
    uniqueness: float,
    subpixel: bool,
    lr_tolerance: float | None,
    speckle_window: int,
    speckle_range: float,
) -> np.ndarray:
    """Winner-take-all with uniqueness and sub-pixel refinement, the left-right check, then
    the speckle filter."""
    from ._kernels import right_disparity, winner_take_all

    disparity: np.ndarray = winner_take_all(volume, d_min, uniqueness, subpixel)
    right = right_disparity(volume, d_min) if lr_tolerance is not None else disparity
    return _checked(disparity, right, lr_tolerance, speckle_window, speckle_range)


def _checked(
    disparity: np.ndarray,
    right: np.ndarray,
    lr_tolerance: float | None,
    speckle_window: int,
    speckle_range: float,
) -> np.ndarray:
    """The left-right check against the right image's disparity, then the speckle filter."""
    if lr_tolerance is not None:
        disparity = left_right_check(disparity, right, lr_tolerance)
    if speckle_window > 0:
        disparity = speckles(disparity, speckle_window, speckle_range)
    return disparity


def _volume(
    left: np.ndarray, right: np.ndarray, d_min: int, count: int, cost: Cost, window: int, block: int
) -> np.ndarray:
    """The cost volume with each pixel's cost summed over the ``block × block`` square."""
    volume = cost_volume(left, right, d_min, count, cost, window)
    if block == 1:
        return volume
    from ._kernels import box_sum

    summed: np.ndarray = box_sum(volume, block // 2)
    return summed
