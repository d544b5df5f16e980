"""Matching descriptors (seed: "correspondences using keypoints")."""

from ._match import match, nearest_two

__all__ = ["match", "nearest_two"]
