"""Cameras (seed: "Camera geometry", "Camera calibration"): the pinhole model
P = K[R | −RC̃], projection, decomposition, lens distortion, checkerboard
corners, calibration (DLT and Zhang) and vanishing points.

Pure functions for other families: :mod:`._projection` (``project_points``,
``distort_pixels``, ``undistort_pixels``, ``decompose_projection``, ...).
"""

from ._calibrate import calibrate_board, calibrate_dlt, dlt_projection, focal_error
from ._corners import board_corners, find_board, grid_spacing, refine_corners, saddle_candidates
from ._draw import draw_board, intrinsics, roundtrip_residual
from ._model import (
    decompose,
    distort_image,
    distort_points,
    pinhole,
    project,
    projection,
    undistort_image,
    undistort_points,
)
from ._projection import (
    decompose_projection,
    distort_normalised,
    distort_pixels,
    look_at,
    normalise_pixels,
    project_points,
    projection_matrix,
    rotation_from_vector,
    undistort_normalised,
    undistort_pixels,
    vector_from_rotation,
)
from ._vanishing import draw_vanishing, horizon, vanishing_error, vanishing_point, vanishing_points
from ._zhang import zhang_intrinsics

__all__ = [
    "board_corners",
    "calibrate_board",
    "calibrate_dlt",
    "decompose",
    "decompose_projection",
    "distort_image",
    "distort_normalised",
    "distort_pixels",
    "distort_points",
    "dlt_projection",
    "draw_board",
    "draw_vanishing",
    "find_board",
    "focal_error",
    "grid_spacing",
    "horizon",
    "intrinsics",
    "look_at",
    "normalise_pixels",
    "pinhole",
    "project",
    "project_points",
    "projection",
    "projection_matrix",
    "refine_corners",
    "rotation_from_vector",
    "roundtrip_residual",
    "saddle_candidates",
    "undistort_image",
    "undistort_normalised",
    "undistort_pixels",
    "undistort_points",
    "vanishing_error",
    "vanishing_point",
    "vanishing_points",
    "vector_from_rotation",
    "zhang_intrinsics",
]
