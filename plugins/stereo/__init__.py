"""Stereo (notes: "Stereo geometry and scene reconstruction", "Active stereo"): disparity
by block matching and semi-global matching, depth and 3-D points, evaluation against
ground truth, rectification (calibrated and uncalibrated), drawings.
"""

from ._cost import cost_volume
from ._depth import depth_from_disparity, depth_points
from ._disparity import block_match, left_right_check, sgm
from ._draw import colour_map, draw_disparity, draw_point_cloud
from ._evaluate import depth_rmse, disparity_error
from ._ports import Depth, DepthPort, Disparity, DisparityPort, Frames, FramesPort
from ._rectify import (
    hartley_homographies,
    rectification_dy,
    rectify_calibrated,
    rectify_pair,
    rectify_uncalibrated,
)

__all__ = [
    "Depth",
    "DepthPort",
    "Disparity",
    "DisparityPort",
    "Frames",
    "FramesPort",
    "block_match",
    "colour_map",
    "cost_volume",
    "depth_from_disparity",
    "depth_points",
    "depth_rmse",
    "disparity_error",
    "draw_disparity",
    "draw_point_cloud",
    "hartley_homographies",
    "left_right_check",
    "rectification_dy",
    "rectify_calibrated",
    "rectify_pair",
    "rectify_uncalibrated",
    "sgm",
]
