"""A simple descriptor: the normalised, oriented, scale-adapted patch around a keypoint."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import Descriptors, GrayImage, Keypoints, node

from ..shared.params import Positive

__all__ = ["patch_descriptor"]


@node("features.patch_descriptor", version=1)
def patch_descriptor(
    image: GrayImage,
    keypoints: Keypoints,
    *,
    size: Annotated[int, Field(ge=3, le=64)] = 8,
    extent: Positive = 6.0,
) -> Descriptors:
    r"""Intensities of a ``size × size`` grid around each keypoint, normalised.

    The grid spans ``extent`` keypoint scales, is rotated to the keypoint's
    orientation and sampled bilinearly (of a Gaussian-smoothed image, against
    aliasing); the values are shifted to zero mean and scaled to unit norm,
    which makes them invariant to affine changes of intensity
    (:math:`I \mapsto aI + b`).

    Parameters
    ----------
    image : GrayImage
        The image the keypoints belong to.
    keypoints : Keypoints
        Where to sample, at each keypoint's scale and orientation.
    size : int
        Side of the sampling grid (the descriptor has ``size²`` values).
    extent : float
        Half-width of the patch in units of the keypoint's scale.

    Returns
    -------
    descriptors : (N, size²) float32
    """
    import scipy.ndimage as ndi

    from ..shared.separable import smooth_gaussian

    if len(keypoints) == 0:
        return np.zeros((0, size * size), np.float32)
    smooth = smooth_gaussian(image.astype(np.float64), 1.0)
    grid = (np.arange(size) - (size - 1) / 2) / size
    gx, gy = np.meshgrid(grid, grid)
    span = extent * keypoints.scale[:, None, None]
    cos = np.cos(keypoints.orientation)[:, None, None]
    sin = np.sin(keypoints.orientation)[:, None, None]
    xs = keypoints.xy[:, 0, None, None] + span * (cos * gx - sin * gy)
    ys = keypoints.xy[:, 1, None, None] + span * (sin * gx + cos * gy)
    values = ndi.map_coordinates(smooth, [ys.ravel(), xs.ravel()], order=1, mode="nearest")
    values = values.reshape(len(keypoints), -1)
    values -= values.mean(axis=1, keepdims=True)
    values /= np.maximum(np.linalg.norm(values, axis=1, keepdims=True), 1e-12)
    return values.astype(np.float32)
