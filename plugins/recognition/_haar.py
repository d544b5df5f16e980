"""Integral images and Haar-like features (seed: "Efficient computation - integral images"):
any rectangle sum in four look-ups, and the five classic feature types at every position
and scale of a window."""

from __future__ import annotations

import functools
import json
from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from graphvision import Array, GrayImage, node

from ..shared.params import Seed
from ._types import Features, FeatureSet, Samples

__all__ = [
    "HAAR_TYPES",
    "haar",
    "haar_corners",
    "haar_feature_table",
    "haar_values",
    "integral_image",
    "integral_image_node",
    "normalised_values",
    "rectangle_sums",
    "sample_haar_features",
    "signed_areas",
    "window_moments",
]

HaarType = Literal["type-2-x", "type-2-y", "type-3-x", "type-3-y", "type-4"]
# per type: its grid of unit rectangles (rows, columns), listed in scikit-image's order
# (row-major, except type-4: top-left, top-right, bottom-right, bottom-left)
HAAR_TYPES: dict[str, tuple[tuple[int, int], list[tuple[int, int]]]] = {
    "type-2-x": ((1, 2), [(0, 0), (0, 1)]),
    "type-2-y": ((2, 1), [(0, 0), (1, 0)]),
    "type-3-x": ((1, 3), [(0, 0), (0, 1), (0, 2)]),
    "type-3-y": ((3, 1), [(0, 0), (1, 0), (2, 0)]),
    "type-4": ((2, 2), [(0, 0), (0, 1), (1, 1), (1, 0)]),
}
ALL_TYPES: tuple[HaarType, ...] = ("type-2-x", "type-2-y", "type-3-x", "type-3-y", "type-4")


def integral_image(images: np.ndarray) -> np.ndarray:
    r"""Zero-padded integral images :math:`S(r, c) = \sum_{r' < r, c' < c} I(r', c')` of
    (..., H, W), float64 (..., H + 1, W + 1); ``S[..., 1:, 1:]`` is scikit-image's."""
    padded = np.zeros((*images.shape[:-2], images.shape[-2] + 1, images.shape[-1] + 1))
    padded[..., 1:, 1:] = images.cumsum(axis=-2, dtype=np.float64).cumsum(axis=-1)
    return padded


@node("recognition.integral_image", version=1)
def integral_image_node(image: GrayImage) -> Array:
    r"""The integral image :math:`S(r, c) = \sum_{r' \le r, c' \le c} I(r', c')`, after which
    any rectangle sum costs four look-ups:
    :math:`\sum = S(r_1, c_1) - S(r_0 - 1, c_1) - S(r_1, c_0 - 1) + S(r_0 - 1, c_0 - 1)`.

    Parameters
    ----------
    image : (H, W) gray image

    Returns
    -------
    integral : (H, W) float64, equal to ``skimage.transform.integral_image``

    References
    ----------
    P. Viola and M. Jones, "Rapid object detection using a boosted cascade of simple
    features", CVPR 2001.
    """
    return integral_image(image)[1:, 1:]


def rectangle_sums(
    padded: np.ndarray, top: np.ndarray, left: np.ndarray, bottom: np.ndarray, right: np.ndarray
) -> np.ndarray:
    """Sums over the rectangles rows ``top..bottom−1`` × columns ``left..right−1`` (arrays of
    equal shape R) of every padded integral image (N, H + 1, W + 1): (N, R)."""
    return (
        padded[:, bottom, right]
        - padded[:, top, right]
        - padded[:, bottom, left]
        + padded[:, top, left]
    )


def haar_feature_table(
    window: tuple[int, int], types: tuple[HaarType, ...] = ALL_TYPES
) -> np.ndarray:
    """Every Haar-like feature of a window: int64 rows (type index, row, col, unit height,
    unit width), the type index into :data:`HAAR_TYPES`; 190,736 rows for 25×25, as many
    as ``skimage.feature.haar_like_feature_coord(25, 25)`` lists. Built once per window
    and types (a detector asks for it at every scale), read-only."""
    return _feature_table(tuple(window), tuple(types))


@functools.lru_cache(maxsize=8)
def _feature_table(window: tuple[int, int], types: tuple[HaarType, ...]) -> np.ndarray:
    height, width = window
    names = list(HAAR_TYPES)
    rows = []
    for name in types:
        (grid_rows, grid_cols), _ = HAAR_TYPES[name]
        for unit_h in range(1, height // grid_rows + 1):
            for unit_w in range(1, width // grid_cols + 1):
                r, c = np.meshgrid(
                    np.arange(height - grid_rows * unit_h + 1),
                    np.arange(width - grid_cols * unit_w + 1),
                    indexing="ij",
                )
                block = np.empty((r.size, 5), np.int64)
                block[:, 0] = names.index(name)
                block[:, 1], block[:, 2] = r.ravel(), c.ravel()
                block[:, 3], block[:, 4] = unit_h, unit_w
                rows.append(block)
    table = np.concatenate(rows) if rows else np.zeros((0, 5), np.int64)
    table.flags.writeable = False
    return table


def haar_values(padded: np.ndarray, table: np.ndarray) -> np.ndarray:
    """Feature values (N, F) of the features ``table`` (F, 5) on padded integral images.

    Rectangle k of a feature enters with sign (−1)^(k+1) in scikit-image's order of
    rectangles, so the values equal ``skimage.feature.haar_like_feature``'s: type-2
    right (bottom) minus left (top), type-3 middle minus the sides, type-4 the
    anti-diagonal minus the diagonal.
    """
    values = np.zeros((len(padded), len(table)))
    for index, (_, offsets) in enumerate(HAAR_TYPES.values()):
        chosen = table[:, 0] == index
        if not chosen.any():
            continue
        _, row, col, unit_h, unit_w = table[chosen].T
        part = np.zeros((len(padded), int(chosen.sum())))
        for k, (dr, dc) in enumerate(offsets):
            top, left = row + dr * unit_h, col + dc * unit_w
            sums = rectangle_sums(padded, top, left, top + unit_h, left + unit_w)
            part += sums if k % 2 else -sums
        values[:, chosen] = part
    return values


SIGMA_FLOOR = 1e-3
"""Least standard deviation a normalised window is divided by (a flat window's features
stay near 0 instead of being blown up by noise)."""


def signed_areas(table: np.ndarray) -> np.ndarray:
    """Σ_k sign_k · area_k of each feature (F,): what a constant image c gives, divided
    by c (0 for the two- and four-rectangle types, −unit area for the three-rectangle
    ones)."""
    offsets = list(HAAR_TYPES.values())
    count = np.array([len(offsets[kind][1]) for kind in table[:, 0]])
    signed = np.where(count == 3, -1.0, 0.0)  # − + −
    return signed * table[:, 3] * table[:, 4]


def window_moments(
    padded: np.ndarray, squared: np.ndarray, top: np.ndarray, left: np.ndarray, window: tuple
) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation (floored at :data:`SIGMA_FLOOR`) of the windows of
    ``window`` (height, width) at rows ``top`` and columns ``left`` (arrays of equal
    shape), from the padded integral images (H + 1, W + 1) of an image and of its
    square."""
    height, width = window
    area = float(height * width)
    total = padded[top + height, left + width] - padded[top, left + width]
    total = total - padded[top + height, left] + padded[top, left]
    total_sq = squared[top + height, left + width] - squared[top, left + width]
    total_sq = total_sq - squared[top + height, left] + squared[top, left]
    mean = total / area
    sigma = np.sqrt(np.maximum(total_sq / area - mean**2, 0.0))
    return mean, np.maximum(sigma, SIGMA_FLOOR)


def normalised_values(
    values: np.ndarray, table: np.ndarray, mean: np.ndarray, sigma: np.ndarray
) -> np.ndarray:
    r"""Feature values (N, F) of windows with mean μ and deviation σ (N,) as they are on
    the window scaled to zero mean and unit variance, :math:`(f - \mu a) / \sigma`
    (a the feature's signed area, :func:`signed_areas`)."""
    return (values - mean[:, None] * signed_areas(table)[None, :]) / sigma[:, None]


def haar_corners(table: np.ndarray, stride: int) -> tuple[np.ndarray, np.ndarray]:
    """The rectangles of features ``table`` (F, 5) as flat offsets (F, 4, 4) of their
    corners (top-left, top-right, bottom-left, bottom-right) from a window's top-left
    corner in a padded integral image with rows of ``stride`` values, and their signs
    (F, 4): ±1 as in :func:`haar_values`, 0 for the rectangles a type lacks."""
    corners = np.zeros((len(table), 4, 4), np.int64)
    signs = np.zeros((len(table), 4), np.float64)
    offsets = list(HAAR_TYPES.values())
    for index, (kind, row, col, unit_h, unit_w) in enumerate(table):
        for k, (dr, dc) in enumerate(offsets[kind][1]):
            top, left = row + dr * unit_h, col + dc * unit_w
            bottom, right = top + unit_h, left + unit_w
            corners[index, k] = (
                top * stride + left,
                top * stride + right,
                bottom * stride + left,
                bottom * stride + right,
            )
            signs[index, k] = 1.0 if k % 2 else -1.0
    return corners, signs


def sample_haar_features(
    window: tuple[int, int], count: int, seed: int, types: tuple[HaarType, ...] = ALL_TYPES
) -> np.ndarray:
    """``count`` features drawn without replacement (seeded) from every feature of the window
    (all of them when ``count`` is 0 or exceeds their number), in table order."""
    table = haar_feature_table(window, types)
    if count == 0 or count >= len(table):
        return table
    chosen = np.random.default_rng(seed).choice(len(table), count, replace=False)
    return table[np.sort(chosen)]


@node("recognition.haar", version=1)
def haar(
    samples: Samples,
    *,
    count: Annotated[int, Field(ge=0, le=100_000)] = 2000,
    types: Annotated[tuple[HaarType, ...], Field(min_length=1)] = ALL_TYPES,
    seed: Seed = 0,
    normalise: bool = False,
) -> Features:
    r"""Haar-like features of each sample: differences of sums over adjacent rectangles
    (two side by side or stacked, three in a row or column, four in a checkerboard) at
    every position and scale in the window, computed from integral images.

    The same parameters draw the same features, so training and test sets computed
    with equal parameters have equal columns. With ``normalise`` each sample is first
    scaled to zero mean and unit variance, as Viola and Jones normalise every window
    (so that lighting and contrast do not matter): a feature f of a window with mean
    μ and deviation σ becomes :math:`(f - \mu a) / \sigma`, a its signed area, with μ
    and σ from the integral images of the window and of its square; a detector
    (``recognition.detect``) then normalises every window the same way.

    Parameters
    ----------
    samples : Samples (N, H, W)
    count : number of features drawn at random from all of the window's (0: all)
    types : feature types drawn from
    seed : seed of the draw
    normalise : scale each window to zero mean and unit variance first

    Returns
    -------
    features : Features (N, count)

    References
    ----------
    P. Viola and M. Jones, "Rapid object detection using a boosted cascade of simple
    features", CVPR 2001.
    """
    window = (samples.images.shape[1], samples.images.shape[2])
    table = sample_haar_features(window, count, seed, types)
    images = samples.images.astype(np.float64)
    padded = integral_image(images)
    values = haar_values(padded, table)
    recipe = {"kind": "haar", "window": list(window), "count": count, "types": list(types)}
    if normalise:
        area = float(window[0] * window[1])
        mean = padded[:, -1, -1] / area
        mean_sq = integral_image(images**2)[:, -1, -1] / area
        sigma = np.maximum(np.sqrt(np.maximum(mean_sq - mean**2, 0.0)), SIGMA_FLOOR)
        values = normalised_values(values, table, mean, sigma)
        recipe["normalise"] = True
    return FeatureSet(values, samples.labels.copy(), json.dumps({**recipe, "seed": seed}))
