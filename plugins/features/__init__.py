"""Local features (seed: "Local features", "Local descriptors"): Harris,
Hessian and LoG detectors, Lowe's DoG detector with orientation assignment,
SIFT and normalised-patch descriptors, and drawings of keypoints and matches.
"""

from ._affine import affine_adapt
from ._corners import harris, harris_response, hessian, log_blobs
from ._dog_pyramid import SiftParams, detect_dog
from ._draw import draw_keypoints, draw_matches
from ._patch import patch_descriptor
from ._sift import describe_sift, dog, sift
from ._sift_descriptors import assign_orientations, sift_descriptors

__all__ = [
    "SiftParams",
    "affine_adapt",
    "assign_orientations",
    "describe_sift",
    "detect_dog",
    "dog",
    "draw_keypoints",
    "draw_matches",
    "harris",
    "harris_response",
    "hessian",
    "log_blobs",
    "patch_descriptor",
    "sift",
    "sift_descriptors",
]
