"""The ``opencv`` backend: OpenCV implementations of the ops other families declare.

Installed with the extra ``graphvision[opencv]`` (opencv-python-headless); OpenCV is
imported only when a run chooses an implementation of this backend
(``--backend opencv,numpy``, ``backends=[...]``, ``backends:`` or a node's
``backend: opencv``). The conventions that differ between the two libraries are
converted in one module, :mod:`.convert`; each op's remaining differences are stated
with its conformance tolerance (``graphvision describe OP``) and checked by
``tests/conformance``.

One package for the whole backend (not an ``opencv.py`` in each family): the extra,
the conversions and the import of ``cv2`` stay in one place, the families' reference
code is untouched by it, and the backend is one entry point that a user can leave out.
"""

from .cascade import cv_lbp_detect
from .filters import cv_box, cv_convolve, cv_correlate, cv_gaussian, cv_median
from .geometry import (
    cv_demosaic,
    cv_gaussian_pyramid,
    cv_homography_ransac,
    cv_match,
    cv_match_template,
    cv_sift,
    cv_warp,
)
from .hough import cv_hough_circles, cv_hough_lines
from .pixels import (
    cv_adaptive_threshold,
    cv_canny,
    cv_close,
    cv_derivative,
    cv_dilate,
    cv_erode,
    cv_from_rgb,
    cv_label,
    cv_open,
    cv_otsu,
    cv_to_gray,
)
from .rectify import cv_rectify_calibrated, cv_rectify_pair
from .stereo import cv_block_match, cv_sgm
from .views import (
    cv_board_corners,
    cv_calibrate_board,
    cv_essential_from_points,
    cv_fundamental,
    cv_relative_pose,
    cv_triangulate,
    cv_undistort_image,
)

__all__ = [
    "cv_adaptive_threshold",
    "cv_block_match",
    "cv_board_corners",
    "cv_box",
    "cv_calibrate_board",
    "cv_canny",
    "cv_close",
    "cv_convolve",
    "cv_correlate",
    "cv_demosaic",
    "cv_derivative",
    "cv_dilate",
    "cv_erode",
    "cv_essential_from_points",
    "cv_from_rgb",
    "cv_fundamental",
    "cv_gaussian",
    "cv_gaussian_pyramid",
    "cv_homography_ransac",
    "cv_hough_circles",
    "cv_hough_lines",
    "cv_label",
    "cv_lbp_detect",
    "cv_match",
    "cv_match_template",
    "cv_median",
    "cv_open",
    "cv_otsu",
    "cv_rectify_calibrated",
    "cv_rectify_pair",
    "cv_relative_pose",
    "cv_sgm",
    "cv_sift",
    "cv_to_gray",
    "cv_triangulate",
    "cv_undistort_image",
    "cv_warp",
]
