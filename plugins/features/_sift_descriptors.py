"""SIFT orientation assignment and descriptors, compiled per (octave, layer) group of
keypoints, with the level's gradients computed only where a keypoint's window reaches
(:mod:`._kernels`)."""

from __future__ import annotations

import numpy as np

from graphvision import KeypointSet

from ._dog_pyramid import _Pyramid

__all__ = [
    "assign_orientations",
    "sift_descriptors",
]


ORIENTATION_BINS = 36


DESCRIPTOR_CELLS = 4


DESCRIPTOR_BINS = 8


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
