"""Lowe's DoG detector, orientation assignment and the SIFT descriptor.

The pyramid is made with the compiled separable Gaussian (incremental
sigmas); the search, refinement and tests of each octave's extrema are one
compiled pass (:mod:`._dog_kernels`); orientations and descriptors are
compiled per (octave, layer) group of keypoints, with the level's gradients
computed only where a keypoint's window reaches (:mod:`._kernels`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Conformance, Descriptors, GrayImage, Keypoints, KeypointSet, node

from ..shared.separable import gaussian_taps, smooth_gaussian

# Lowe's parameters, defined once for every SIFT node (defaults as in the paper and OpenCV).
Intervals = Annotated[int, Field(ge=1, le=8, description="Scales per octave, s.")]
BaseSigma = Annotated[float, Field(gt=0, description="Blur of each octave's first scale.")]
Contrast = Annotated[float, Field(ge=0, description="Least |D| at a refined extremum.")]
EdgeRatio = Annotated[float, Field(gt=1, description="Largest ratio of principal curvatures.")]

__all__ = [
    "SiftParams",
    "assign_orientations",
    "describe_sift",
    "detect_dog",
    "dog",
    "sift",
    "sift_descriptors",
]

BORDER = 5
ORIENTATION_BINS = 36
DESCRIPTOR_CELLS = 4
DESCRIPTOR_BINS = 8


@dataclass(frozen=True)
class SiftParams:
    """Lowe's parameters (defaults as in the paper and OpenCV)."""

    intervals: int = 3
    sigma: float = 1.6
    contrast_threshold: float = 0.04
    edge_ratio: float = 10.0
    upsample: bool = True
    max_keypoints: int = 0


@dataclass
class _Pyramid:
    gaussians: list[np.ndarray]  # per octave: (intervals + 3, H, W) float32
    dogs: list[np.ndarray]  # per octave: (intervals + 2, H, W) float32
    factor: float  # input pixels per octave-0 pixel (0.5 when upsampled)
    shift: float  # input coordinate of octave-0 pixel 0 (-0.25 when upsampled)
    params: SiftParams
    # (octave, layer) -> (magnitude, angle, done): gradients filled on demand by the kernels
    gradients: dict = field(default_factory=dict)

    def layer_sigma(self, layer: np.ndarray) -> np.ndarray:
        """Blur, in octave pixels, of the (fractional) layer."""
        return self.params.sigma * 2.0 ** (layer / self.params.intervals)


@functools.lru_cache(maxsize=64)
def _reflected(length: int, half: int) -> np.ndarray:
    """Source index of each position of a line of ``length`` padded by ``half`` (reflect)."""
    return np.pad(np.arange(length, dtype=np.int64), half, mode="symmetric")


def _blur_stack(stack: np.ndarray, steps: list[float]) -> None:
    """``stack[i] = smooth_gaussian(stack[i - 1], steps[i - 1], truncate=3.0)``, in place.

    The same compiled separable kernel writing straight into the octave's stack
    (no temporary level and copy), the boundary indices made once per size.
    """
    from ..shared.separable_kernels import correlate_both

    rows, cols = stack.shape[1:]
    for i, step in enumerate(steps, start=1):
        taps = gaussian_taps(step, 3.0).astype(np.float32)
        half = taps.size // 2
        correlate_both(
            stack[i - 1], taps, 1, _reflected(rows, half), taps, 1, _reflected(cols, half), stack[i]
        )


def _pyramid(image: np.ndarray, params: SiftParams) -> _Pyramid:
    from ._dog_kernels import upsample_twice

    base = np.ascontiguousarray(image, np.float32)
    assumed = 0.5
    factor = 1.0
    shift = 0.0
    if params.upsample:
        # pixel centres: up-sampled pixel j sits at input coordinate j / 2 - 1/4
        base = upsample_twice(base)  # = ndi.zoom(base, 2, order=1, grid_mode=True, mode="nearest")
        assumed, factor, shift = 1.0, 0.5, -0.25
    base = smooth_gaussian(base, math.sqrt(max(params.sigma**2 - assumed**2, 0.01)))
    s = params.intervals
    octaves = max(1, int(math.log2(min(base.shape))) - 3)
    totals = [params.sigma * 2.0 ** (i / s) for i in range(s + 3)]
    steps = [math.sqrt(totals[i] ** 2 - totals[i - 1] ** 2) for i in range(1, s + 3)]
    gaussians, dogs = [], []
    for _ in range(octaves):
        stack = np.empty((s + 3, *base.shape), np.float32)
        stack[0] = base
        _blur_stack(stack, steps)
        gaussians.append(stack)
        dogs.append(np.diff(stack, axis=0))
        base = stack[s][::2, ::2]
        if min(base.shape) < 2 * BORDER + 4:
            break
    return _Pyramid(gaussians, dogs, factor, shift, params)


def detect_dog(
    image: np.ndarray, params: SiftParams = SiftParams()
) -> tuple[KeypointSet, _Pyramid, np.ndarray]:
    """DoG keypoints (without orientation) and the pyramid they were found in.

    Returns the keypoints in input coordinates, the pyramid, and for each
    keypoint its (octave, layer, x, y) in octave coordinates.
    """

    from ._dog_kernels import octave_keypoints

    pyramid = _pyramid(image, params)
    s = params.intervals
    prefilter = 0.5 * params.contrast_threshold / s
    found = []
    for octave, dog in enumerate(pyramid.dogs):
        rows = octave_keypoints(
            dog, prefilter, params.contrast_threshold / s, params.edge_ratio, s, BORDER
        )
        found.append(np.column_stack([np.full(len(rows), octave), rows]))
    table = np.vstack(found) if found else np.zeros((0, 5))
    if params.max_keypoints and len(table) > params.max_keypoints:
        table = table[np.argsort(-table[:, 4], kind="stable")[: params.max_keypoints]]
    octaves, layer, ox, oy, response = table.T
    scale_to_input = pyramid.factor * 2.0**octaves
    keypoints = KeypointSet(
        np.column_stack([ox * scale_to_input, oy * scale_to_input]) + pyramid.shift,
        pyramid.layer_sigma(layer) * scale_to_input,
        np.zeros(len(table)),
        response.astype(np.float64),
    )
    return keypoints, pyramid, table[:, :4]


def _gradients(pyramid: _Pyramid, octave: int, layer: int) -> tuple[np.ndarray, ...]:
    """The level's image and its gradient arrays (magnitude, angle, done), filled on demand."""
    key = (octave, layer)
    image = pyramid.gaussians[octave][layer]
    if key not in pyramid.gradients:
        pyramid.gradients[key] = (
            np.empty(image.shape, np.float32),
            np.empty(image.shape, np.float32),
            np.zeros(image.shape, np.bool_),
        )
    return (image, *pyramid.gradients[key])


def _groups(where: np.ndarray):
    """Yield (octave, integer layer, indices) for keypoints at (octave, layer, x, y)."""
    nearest = np.round(where[:, 1]).astype(int)
    keys = where[:, 0].astype(int) * 100 + nearest
    for key in np.unique(keys):
        index = np.flatnonzero(keys == key)
        yield int(key // 100), int(key % 100), index


def assign_orientations(
    pyramid: _Pyramid, where: np.ndarray, keypoints: KeypointSet
) -> tuple[KeypointSet, np.ndarray]:
    """One keypoint per orientation peak within 80% of the strongest (Lowe 2004, section 5).

    A 36-bin histogram of gradient orientations around each keypoint,
    weighted by magnitude and a Gaussian of 1.5σ, smoothed; every local peak
    above 0.8 of the maximum gives a keypoint, its angle refined by a parabola.
    """
    from ._kernels import orientation_histograms

    out_index, out_angle = [], []
    for octave, layer, index in _groups(where):
        image, magnitude, angle, done = _gradients(pyramid, octave, layer)
        smooth = orientation_histograms(
            image,
            magnitude,
            angle,
            done,
            where[index, 2].copy(),
            where[index, 3].copy(),
            1.5 * pyramid.layer_sigma(where[index, 1]),
            ORIENTATION_BINS,
        )
        left, right = np.roll(smooth, 1, 1), np.roll(smooth, -1, 1)
        peaks = (
            (smooth > left) & (smooth > right) & (smooth >= 0.8 * smooth.max(axis=1, keepdims=True))
        )
        which, peak_bin = np.nonzero(peaks)
        l, c, r = left[which, peak_bin], smooth[which, peak_bin], right[which, peak_bin]
        shift = 0.5 * (l - r) / (l - 2 * c + r)
        theta = (peak_bin + 0.5 + shift) * 2 * np.pi / ORIENTATION_BINS
        out_index.append(index[which])
        out_angle.append(np.mod(theta, 2 * np.pi))
    if not out_index:
        return keypoints, where
    order = np.concatenate(out_index)
    oriented = keypoints.take(order)
    oriented = KeypointSet(
        oriented.xy, oriented.scale, np.concatenate(out_angle), oriented.response
    )
    return oriented, where[order]


def sift_descriptors(pyramid: _Pyramid, where: np.ndarray, orientation: np.ndarray) -> np.ndarray:
    r"""128-d SIFT descriptors (Lowe 2004, section 6), one (octave, layer) group at a time.

    A grid of 4×4 cells of width :math:`3\sigma` around the keypoint, rotated
    to its orientation; each pixel's gradient, weighted by its magnitude and a
    Gaussian of half the window, votes into 8 orientation bins of the cells
    with trilinear interpolation (over row, column and orientation). The 128
    values are normalised, clipped at 0.2 and renormalised. The scatter loop
    is compiled with numba (:mod:`._kernels`).
    """
    from ._kernels import descriptor_histograms

    d, n = DESCRIPTOR_CELLS, DESCRIPTOR_BINS
    out = np.zeros((len(where), d * d * n), np.float32)
    for octave, layer, index in _groups(where):
        width = 3.0 * pyramid.layer_sigma(where[index, 1])
        image, magnitude, angle, done = _gradients(pyramid, octave, layer)
        out[index] = descriptor_histograms(
            image,
            magnitude,
            angle,
            done,
            where[index, 2].copy(),
            where[index, 3].copy(),
            width,
            orientation[index].astype(np.float64),
            d,
            n,
        )
    norm = np.linalg.norm(out, axis=1, keepdims=True)
    out /= np.maximum(norm, 1e-12)
    np.minimum(out, 0.2, out=out)
    out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)
    return out


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
