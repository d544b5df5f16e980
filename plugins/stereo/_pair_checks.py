"""Checks of a stereo pair before matching: one size, a disparity range that fits, and a
cost volume this machine holds."""

from __future__ import annotations

import numpy as np

__all__ = [
    "MAX_VOLUME",
    "check_pair",
]


MAX_VOLUME = 2**27
"""Most values of a cost volume (512 MB in float32): semi-global matching keeps a few of
them at once, so this is what this machine holds; a 500 × 741 pair with 64 disparities
(stereo.yaml) needs 23.7 million."""


def check_pair(left: np.ndarray, right: np.ndarray, d_min: int, count: int, window: int) -> None:
    """Refuse a pair of different sizes, a range wider than the image, and a cost volume
    (rows × columns × disparities) beyond ``MAX_VOLUME`` values, saying what it needs."""
    if left.shape != right.shape:
        raise ValueError(
            f"the left image is {left.shape[0]}×{left.shape[1]} (rows×columns) but the right is"
            f" {right.shape[0]}×{right.shape[1]}: a rectified pair has one size"
        )
    cols = left.shape[1]
    if abs(d_min) + count > cols:
        raise ValueError(
            f"the disparity range [{d_min}, {d_min + count - 1}] does not fit in the image's "
            f"{cols} columns: lower num_disparities or min_disparity"
        )
    volume = left.shape[0] * cols * count
    if volume > MAX_VOLUME:
        raise ValueError(
            f"the cost volume {left.shape[0]}×{cols}×{count} would hold {volume:,} values "
            f"({volume * 4 / 2**30:.1f} GiB as float32, more again to aggregate it), at most "
            f"{MAX_VOLUME:,}: lower num_disparities or match smaller images"
        )
