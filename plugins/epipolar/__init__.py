"""Two views (notes: "Multiple-view geometry", "Stereo geometry and scene reconstruction"):
the fundamental and essential matrices, relative pose, triangulation (linear and
non-linear), epipolar lines and epipoles with a drawing.
"""

from ._fundamental import essential, essential_from_points, fundamental
from ._geometry import (
    eight_point,
    essential_from_fundamental,
    poses_from_essential,
    sampson_distance,
    triangulate_linear,
    triangulate_nonlinear,
)
from ._lines import draw_epipolar, epipolar_lines, epipoles, lines_from_coefficients
from ._nodes import (
    matched_points,
    mean_abs_dy,
    pose_error,
    relative_pose,
    reprojection_errors,
    reprojection_rms,
    triangulate,
)
from ._ports import EssentialPort, FundamentalPort

__all__ = [
    "EssentialPort",
    "FundamentalPort",
    "draw_epipolar",
    "eight_point",
    "epipolar_lines",
    "epipoles",
    "essential",
    "essential_from_fundamental",
    "essential_from_points",
    "fundamental",
    "lines_from_coefficients",
    "matched_points",
    "mean_abs_dy",
    "pose_error",
    "poses_from_essential",
    "relative_pose",
    "reprojection_errors",
    "reprojection_rms",
    "sampson_distance",
    "triangulate",
    "triangulate_linear",
    "triangulate_nonlinear",
]
