"""Lowe's DoG detector, orientation assignment and the SIFT descriptor.

The pyramid is made with the compiled separable Gaussian (incremental
sigmas); the search, refinement and tests of each octave's extrema are one
compiled pass (:mod:`._dog_kernels`); orientations and descriptors are
compiled per (octave, layer) group of keypoints, with the level's gradients
computed only where a keypoint's window reaches (:mod:`._kernels`).
"""

from __future__ import annotations

from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Conformance, Descriptors, GrayImage, Keypoints, KeypointSet, node

from ._dog_pyramid import SiftParams, _Pyramid, _pyramid, detect_dog
from ._sift_descriptors import (
    DESCRIPTOR_BINS,
    DESCRIPTOR_CELLS,
    assign_orientations,
    sift_descriptors,
)

# Lowe's parameters, defined once for every SIFT node (defaults as in the paper and OpenCV).
Intervals = Annotated[int, Field(ge=1, le=8, description="Scales per octave, s.")]
BaseSigma = Annotated[float, Field(gt=0, description="Blur of each octave's first scale.")]
Contrast = Annotated[float, Field(ge=0, description="Least |D| at a refined extremum.")]
EdgeRatio = Annotated[float, Field(gt=1, description="Largest ratio of principal curvatures.")]

__all__ = [
    "describe_sift",
    "dog",
    "sift",
]


class SiftFeatures(NamedTuple):
    keypoints: Keypoints
    descriptors: Descriptors


@node(
    "features.sift",
    version=1,
    conformance=Conformance(
        "recall",
        0.8,
        radius=1.5,
        note=(
            "OpenCV detects on the 8-bit image and always doubles it first; its descriptors are "
            "renormalised to unit length"
        ),
    ),
)
def sift(
    image: GrayImage,
    *,
    intervals: Intervals = 3,
    sigma: BaseSigma = 1.6,
    contrast_threshold: Contrast = 0.04,
    edge_ratio: EdgeRatio = 10.0,
    upsample: bool = True,
    max_keypoints: Annotated[int, Field(ge=0)] = 0,
) -> SiftFeatures:
    r"""Lowe's DoG keypoints with orientations and SIFT descriptors.

    **Detector.** A Gaussian pyramid (image doubled first with ``upsample``),
    ``intervals`` scales per octave (:math:`k = 2^{1/s}`, base blur
    :math:`\sigma`); the difference of adjacent Gaussians approximates the
    scale-normalised LoG, :math:`D = G(k\sigma) * I - G(\sigma) * I`. Keypoints
    are extrema among their 26 neighbours (8 in their scale, 9 above, 9
    below), refined to sub-pixel and sub-scale precision by a quadratic fit
    (:math:`\hat x = -H^{-1} \nabla D`), dropped when of low contrast
    (:math:`|D(\hat x)| < t / s`) or on an edge
    (:math:`\mathrm{tr}(H)^2 / \det H \ge (r + 1)^2 / r`, :math:`r` = ``edge_ratio``).

    **Orientation.** Every peak of the 36-bin gradient orientation histogram
    within 80% of the highest gives its own keypoint.

    **Descriptor.** 4×4 cells × 8 orientations = 128 values, Gaussian
    weighted, trilinearly interpolated, normalised, clipped at 0.2,
    renormalised.

    Parameters
    ----------
    image : (H, W) float32
    intervals, sigma, contrast_threshold, edge_ratio, upsample
        Lowe's parameters (defaults as in the paper and OpenCV).
    max_keypoints : int
        Keep the strongest (0: all).

    Returns
    -------
    keypoints : positions, scales (σ in input pixels), orientations, |D| responses
    descriptors : (N, 128) float32

    References
    ----------
    .. [1] D. G. Lowe, "Distinctive image features from scale-invariant
       keypoints", IJCV 60(2), 2004.
    .. [2] M. Brown, D. G. Lowe, "Invariant features from interest point
       groups", BMVC 2002 (sub-pixel refinement).
    """
    params = SiftParams(intervals, sigma, contrast_threshold, edge_ratio, upsample, max_keypoints)
    keypoints, pyramid, where = detect_dog(image, params)
    keypoints, where = assign_orientations(pyramid, where, keypoints)
    descriptors = sift_descriptors(pyramid, where, keypoints.orientation)
    return SiftFeatures(keypoints, descriptors)


@node("features.dog", version=1)
def dog(
    image: GrayImage,
    *,
    intervals: Intervals = 3,
    sigma: BaseSigma = 1.6,
    contrast_threshold: Contrast = 0.04,
    edge_ratio: EdgeRatio = 10.0,
    upsample: bool = True,
) -> Keypoints:
    r"""Lowe's DoG keypoints with orientations (the detector half of ``features.sift``).

    Parameters
    ----------
    image : GrayImage
        The image to detect in.
    intervals : int
        Scales per octave, s; the DoG stack has s + 2 levels per octave.
    sigma : float
        Blur of the first scale of each octave (Lowe: 1.6).
    contrast_threshold : float
        Minimum absolute DoG response at the refined extremum (image in [0, 1]).
    edge_ratio : float
        Maximum ratio r of the Hessian's principal curvatures: keep
        :math:`\operatorname{tr}^2 / \det < (r + 1)^2 / r`.
    upsample : bool
        Double the image first (octave −1), which finds about four times more keypoints.

    Returns
    -------
    keypoints : one per orientation peak (see ``features.sift``)
    """
    params = SiftParams(intervals, sigma, contrast_threshold, edge_ratio, upsample)
    keypoints, pyramid, where = detect_dog(image, params)
    return assign_orientations(pyramid, where, keypoints)[0]


def _locate(pyramid: _Pyramid, keypoints: KeypointSet) -> np.ndarray:
    """(octave, layer, x, y) in pyramid coordinates of keypoints given in input coordinates."""
    s = pyramid.params.intervals
    total = s * np.log2(np.maximum(keypoints.scale, 1e-6) / (pyramid.params.sigma * pyramid.factor))
    octave = np.clip(np.floor(total / s), 0, len(pyramid.gaussians) - 1)
    layer = np.clip(total - octave * s, 0, s + 2)
    step = pyramid.factor * 2.0**octave
    xy = (keypoints.xy - pyramid.shift) / step[:, None]
    return np.column_stack([octave, layer, xy])


@node("features.describe_sift", version=1)
def describe_sift(
    image: GrayImage,
    keypoints: Keypoints,
    *,
    intervals: Intervals = 3,
    sigma: BaseSigma = 1.6,
    upsample: bool = True,
) -> Descriptors:
    """SIFT descriptors of given keypoints (any detector), at their scales and orientations.

    Each keypoint is described in the Gaussian pyramid level nearest its
    scale, exactly as ``features.sift`` describes its own keypoints, so
    ``describe_sift(image, sift(image).keypoints)`` reproduces its descriptors.

    Parameters
    ----------
    image : GrayImage
        The image the keypoints belong to.
    keypoints : Keypoints
        Keypoints from any detector (positions, scales, orientations).
    intervals : int
        Scales per octave of the Gaussian scale space the descriptors are sampled in.
    sigma : float
        Blur of the first scale of each octave.
    upsample : bool
        Double the image first (Lowe's octave −1), as the detector did.

    Returns
    -------
    descriptors : (N, 128) float32
    """
    params = SiftParams(intervals, sigma, upsample=upsample)
    if len(keypoints) == 0:
        return np.zeros((0, DESCRIPTOR_CELLS * DESCRIPTOR_CELLS * DESCRIPTOR_BINS), np.float32)
    pyramid = _pyramid(image, params)
    return sift_descriptors(pyramid, _locate(pyramid, keypoints), keypoints.orientation)
