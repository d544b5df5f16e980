"""Homographies (seed: "Homography"): normalised DLT, RANSAC estimation,
perspective warps, seeded random warps, corner error, two-view stitching.
"""

from ._homography import (
    apply_homography,
    corner_error,
    estimate_homography,
    homography_ransac,
    normalising_transform,
    refine_homography,
    transfer_error,
)
from ._warp import random_warp, stitch, two_views, warp

__all__ = [
    "apply_homography",
    "corner_error",
    "estimate_homography",
    "homography_ransac",
    "normalising_transform",
    "random_warp",
    "refine_homography",
    "stitch",
    "transfer_error",
    "two_views",
    "warp",
]
