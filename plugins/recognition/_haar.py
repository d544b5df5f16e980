"""Integral images and Haar-like features (seed: "Efficient computation - integral images"):
any rectangle sum in four look-ups, and the five classic feature types at every position
and scale of a window."""

from __future__ import annotations

import json
from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from graphvision import Array, GrayImage, node

from .._params import Seed
from ._types import Features, FeatureSet, Samples

__all__ = [
    "HAAR_TYPES",
    "haar",
    "haar_feature_table",
    "haar_values",
    "integral_image",
    "integral_image_node",
    "rectangle_sums",
    "sample_haar_features",
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
    as ``skimage.feature.haar_like_feature_coord(25, 25)`` lists."""
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
    return np.concatenate(rows) if rows else np.zeros((0, 5), np.int64)


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
) -> Features:
    """Haar-like features of each sample: differences of sums over adjacent rectangles
    (two side by side or stacked, three in a row or column, four in a checkerboard) at
    every position and scale in the window, computed from integral images.

    The same parameters draw the same features, so training and test sets computed
    with equal parameters have equal columns.

    Parameters
    ----------
    samples : Samples (N, H, W)
    count : number of features drawn at random from all of the window's (0: all)
    types : feature types drawn from
    seed : seed of the draw

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
    values = haar_values(integral_image(samples.images), table)
    recipe = {"kind": "haar", "window": list(window), "count": count, "types": list(types)}
    return FeatureSet(values, samples.labels.copy(), json.dumps({**recipe, "seed": seed}))
