"""Stereo (notes: "Stereo geometry and scene reconstruction", "Active stereo"): disparity
by block matching and semi-global matching, depth and 3-D points, evaluation against
ground truth, rectification (calibrated and uncalibrated), structured light, drawings.
"""

from ._colour_map import colour_map
from ._cost import cost_volume
from ._depth import ColouredPoints, coloured_points, depth_from_disparity, depth_points
from ._disparity import block_match, sgm
from ._draw import draw_disparity, draw_point_cloud
from ._evaluate import depth_rmse, disparity_error
from ._ports import (
    Depth,
    DepthPort,
    Disparity,
    DisparityPort,
    Frames,
    FramesPort,
    PointColours,
    PointColoursPort,
)
from ._rectify import (
    hartley_homographies,
    rectification_dy,
    rectify_calibrated,
    rectify_pair,
    rectify_uncalibrated,
)
from ._selection import left_right_check
from ._speckles import filter_speckles
from ._structured import Stripes, StripesPort, decode_gray_code, depth_from_stripes

__all__ = [
    "ColouredPoints",
    "Depth",
    "DepthPort",
    "Disparity",
    "DisparityPort",
    "Frames",
    "FramesPort",
    "PointColours",
    "PointColoursPort",
    "Stripes",
    "StripesPort",
    "block_match",
    "colour_map",
    "coloured_points",
    "cost_volume",
    "decode_gray_code",
    "depth_from_disparity",
    "depth_from_stripes",
    "depth_points",
    "depth_rmse",
    "disparity_error",
    "draw_disparity",
    "draw_point_cloud",
    "filter_speckles",
    "hartley_homographies",
    "left_right_check",
    "rectification_dy",
    "rectify_calibrated",
    "rectify_pair",
    "rectify_uncalibrated",
    "sgm",
]
