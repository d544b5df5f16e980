"""ROI pooling (Fast R-CNN): a fixed-size max pooling of any box of a feature map.

A box (x0, y0, x1, y1) in image pixels goes to the feature map of ``stride`` pixels per
cell as ``round(x / stride)`` for each coordinate (half up; the end exclusive, clipped to
the map and at least one cell past the start), and is divided into ``size`` × ``size`` cells: cell
(i, j) spans rows ``y0 + ⌊i·h / size⌋`` to ``y0 + ⌈(i + 1)·h / size⌉`` (exclusive; the
same in x), so cells cover the ROI, never empty, overlapping by one row or column when
``size`` does not divide the ROI (Girshick's Caffe layer). On an integer-aligned box
whose sides are multiples of ``size`` the cells are the blocks of a plain max pooling of
the crop.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import Array, Boxes, node

__all__ = ["feature_rois", "pool_rois", "roi_pool"]


def feature_rois(xyxy: np.ndarray, stride: int, shape: tuple[int, int]) -> np.ndarray:
    """Boxes in image pixels as int64 ROIs of a feature map of ``shape`` (rows, cols) and
    ``stride``: each coordinate rounded (half up) to a cell edge, then clipped so that the
    ROI holds at least one cell of the map. ValueError naming the first box that starts
    before the map or ends more than one cell past it (the map covers
    ``cols · stride`` × ``rows · stride`` pixels)."""
    rows, cols = shape
    outside = (
        (xyxy[:, 0] < 0)
        | (xyxy[:, 1] < 0)
        | (xyxy[:, 2] > (cols + 1) * stride)
        | (xyxy[:, 3] > (rows + 1) * stride)
    )
    if outside.any():
        index = int(np.flatnonzero(outside)[0])
        raise ValueError(
            f"ROI {index} {xyxy[index].tolist()} lies outside the {rows}×{cols} feature map "
            f"(stride {stride}: it covers x in [0, {cols * stride}], y in [0, {rows * stride}])"
        )
    rois = np.floor(xyxy / stride + 0.5).astype(np.int64)
    rois[:, 0] = np.minimum(rois[:, 0], cols - 1)
    rois[:, 1] = np.minimum(rois[:, 1], rows - 1)
    rois[:, 2] = np.clip(rois[:, 2], rois[:, 0] + 1, cols)
    rois[:, 3] = np.clip(rois[:, 3], rois[:, 1] + 1, rows)
    return rois


def pool_rois(features: np.ndarray, xyxy: np.ndarray, stride: int, size: int) -> np.ndarray:
    """ROI max pooling of ``features`` (C, H, W) over boxes ``xyxy`` (R, 4) in image
    pixels: (R, C, size, size) float64."""
    from ._kernels import roi_max_pool  # numba compiles (or loads its cache) on first use

    rois = feature_rois(xyxy, stride, features.shape[1:])
    return roi_max_pool(np.ascontiguousarray(features, np.float64), rois, size)


@node("detection.roi_pool", version=1)
def roi_pool(
    features: Array,
    boxes: Boxes,
    *,
    size: Annotated[int, Field(ge=1, le=16)] = 4,
    stride: Annotated[int, Field(ge=1, le=64)] = 1,
) -> Array:
    """Fast R-CNN's ROI pooling: each box of a feature map max-pooled into ``size`` ×
    ``size`` cells.

    A box goes to map cells as round(x / stride) (half up, end exclusive); cell (i, j)
    spans rows ``y0 + ⌊i·h/size⌋ .. y0 + ⌈(i+1)·h/size⌉`` and the same in x.

    Parameters
    ----------
    features : Array
        A feature map (C, H, W) or a single-channel map or image (H, W).
    boxes : Boxes
        Regions (x0, y0, x1, y1) in image pixels.
    size : int
        Output cells per side.
    stride : int
        Image pixels per feature-map cell.

    Returns
    -------
    Array
        (R, C, size, size) float64.

    References
    ----------
    R. Girshick, "Fast R-CNN", ICCV 2015, section 2.1.
    """
    stack = features[None] if features.ndim == 2 else features
    if stack.ndim != 3 or not np.isfinite(stack).all():
        raise ValueError(f"features must be a finite (C, H, W) or (H, W) map, got {features.shape}")
    return pool_rois(stack, boxes.xyxy, stride, size)
