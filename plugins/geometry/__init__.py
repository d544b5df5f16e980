"""Homographies (seed: "Homography"): normalised DLT, RANSAC estimation,
perspective warps, corner error, two-view stitching (random warps with
their truth are in the ``synthetic`` family).
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
from ._warp import sample_homography, stitch, warp

__all__ = [
    "apply_homography",
    "corner_error",
    "estimate_homography",
    "homography_ransac",
    "normalising_transform",
    "refine_homography",
    "sample_homography",
    "stitch",
    "transfer_error",
    "warp",
]
