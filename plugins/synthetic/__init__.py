"""Synthetic data with known truth: noise, random warps, sampled lines, scenes of digits,
shapes with a class at every pixel, and photographs with known faces.

Every node here is seeded and returns what a test or a benchmark measures
against (the homography of a warp, the line the points were drawn from).
Algorithms never live here; other families' tests and pipelines use these
nodes as their ground truth.
"""

from ._boards import board_object_points, board_views, plane_view, render_board
from ._depth import depth_plane
from ._digit_scenes import Scenes, SceneSet, ScenesPort, digit_scenes, render_digit_scenes
from ._face_collage import face_collage, face_scenes
from ._instance_scenes import InstanceScenes, instance_scenes, render_instance_scenes
from ._lines import line_points
from ._noise import gaussian_noise, impulse_noise, salt_and_pepper
from ._object_scene_set import ObjectScenes, ObjectSceneSet, ObjectScenesPort
from ._object_scenes import object_scenes, render_object_scenes
from ._planar_stereo import PHOTOGRAPHS, planar_stereo_scene
from ._plane_lines import plane_lines
from ._shape_scenes import LabelledScenes, LabelledSceneSet, LabelledScenesPort, shape_scenes
from ._stereo_pair import stereo_pair
from ._structured_light import gray_code_stripes, structured_light_scene
from ._turned_view import turned_view
from ._two_view import two_view_scene
from ._warps import random_homography, random_warp, two_views

__all__ = [
    "PHOTOGRAPHS",
    "InstanceScenes",
    "LabelledSceneSet",
    "LabelledScenes",
    "LabelledScenesPort",
    "ObjectSceneSet",
    "ObjectScenes",
    "ObjectScenesPort",
    "SceneSet",
    "Scenes",
    "ScenesPort",
    "board_object_points",
    "board_views",
    "depth_plane",
    "digit_scenes",
    "face_collage",
    "face_scenes",
    "gaussian_noise",
    "gray_code_stripes",
    "impulse_noise",
    "instance_scenes",
    "line_points",
    "object_scenes",
    "planar_stereo_scene",
    "plane_lines",
    "plane_view",
    "random_homography",
    "random_warp",
    "render_board",
    "render_digit_scenes",
    "render_instance_scenes",
    "render_object_scenes",
    "salt_and_pepper",
    "shape_scenes",
    "stereo_pair",
    "structured_light_scene",
    "turned_view",
    "two_view_scene",
    "two_views",
]
