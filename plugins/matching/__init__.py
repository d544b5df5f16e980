"""Matching descriptors (seed: "correspondences using keypoints") and detection by
feature constellations (seed: "Object detection by feature constellations"): instances
of a model found by Hough voting of SIFT matches and verified by affine and homography
fits (Lowe 2004, section 7).
"""

from ._constellation import (
    ConstellationParams,
    Instances,
    InstanceSet,
    InstancesPort,
    draw_object_scenes,
    find_instances,
    find_instances_in_scenes,
    match_instances,
    score_instances,
)
from ._match import match, nearest_two

__all__ = [
    "ConstellationParams",
    "InstanceSet",
    "Instances",
    "InstancesPort",
    "draw_object_scenes",
    "find_instances",
    "find_instances_in_scenes",
    "match",
    "match_instances",
    "nearest_two",
    "score_instances",
]
