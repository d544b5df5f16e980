"""Two views (notes: "Multiple-view geometry", "Stereo geometry and scene reconstruction"):
the fundamental and essential matrices, relative pose, triangulation.
"""

from ._geometry import (
    eight_point,
    essential_from_fundamental,
    poses_from_essential,
    sampson_distance,
    triangulate_linear,
)
from ._nodes import (
    EssentialPort,
    FundamentalPort,
    essential,
    fundamental,
    matched_points,
    mean_abs_dy,
    pose_error,
    relative_pose,
    reprojection_rms,
    triangulate,
)

__all__ = [
    "EssentialPort",
    "FundamentalPort",
    "eight_point",
    "essential",
    "essential_from_fundamental",
    "fundamental",
    "matched_points",
    "mean_abs_dy",
    "pose_error",
    "poses_from_essential",
    "relative_pose",
    "reprojection_rms",
    "sampson_distance",
    "triangulate",
    "triangulate_linear",
]
