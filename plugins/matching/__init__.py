"""Matching descriptors (seed: "correspondences using keypoints") and detection by
feature constellations (seed: "Object detection by feature constellations"): instances
of a model found by Hough voting of SIFT matches and verified by affine and homography
fits (Lowe 2004, section 7).
"""

from ._constellation import find_instances, find_instances_in_scenes
from ._instances import Instances, InstanceSet, InstancesPort
from ._match import match, nearest_two
from ._model_views import ConstellationParams
from ._pictures import draw_object_scenes
from ._scores import match_instances, score_instances

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
