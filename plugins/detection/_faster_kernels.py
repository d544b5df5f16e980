"""numba kernel of ROI max pooling that also returns where each maximum came from, so the
gradient of the pooled features flows back into the feature map (Fast R-CNN's ROI pooling
layer, trained end to end). Imported on first use: numba loads slowly."""

from __future__ import annotations

import numpy as np

from ..shared.jit import njit

__all__ = ["roi_max_pool_argmax"]


@njit(cache=True, nogil=True)
def roi_max_pool_argmax(features, rois, size):  # pragma: no cover (compiled)
    """Max pooling of ``features`` (C, H, W) over each ROI (R, 4) int64 (x0, y0, x1, y1),
    exclusive ends, inside the map, into ``size`` × ``size`` cells (the cells of
    ``_kernels.roi_max_pool``), and the flat index ``c·H·W + y·W + x`` of each maximum."""
    count = rois.shape[0]
    channels, rows, cols = features.shape
    out = np.empty((count, channels, size, size))
    where = np.empty((count, channels, size, size), np.int64)
    for r in range(count):
        x0, y0, x1, y1 = rois[r, 0], rois[r, 1], rois[r, 2], rois[r, 3]
        height = y1 - y0
        width = x1 - x0
        for i in range(size):
            top = y0 + (i * height) // size
            bottom = y0 + -((-(i + 1) * height) // size)
            for j in range(size):
                left = x0 + (j * width) // size
                right = x0 + -((-(j + 1) * width) // size)
                for c in range(channels):
                    best = -np.inf
                    at = c * rows * cols + top * cols + left
                    for y in range(top, bottom):
                        for x in range(left, right):
                            if features[c, y, x] > best:
                                best = features[c, y, x]
                                at = c * rows * cols + y * cols + x
                    out[r, c, i, j] = best
                    where[r, c, i, j] = at
    return out, where


@njit(cache=True, nogil=True)
def greedy_nms(boxes, iou, most):  # pragma: no cover (compiled)
    """Greedy non-maximum suppression of ``boxes`` (N, 4) already sorted best first: the
    indices of the kept boxes (each overlapping no earlier kept box by IoU above ``iou``),
    at most ``most`` of them (``shared.boxes.non_max_suppression`` without the scores)."""
    count = boxes.shape[0]
    keep = np.empty(min(count, most), np.int64)
    kept = 0
    area = (boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1])
    for i in range(count):
        if kept == most:
            break
        alive = True
        for m in range(kept):
            j = keep[m]
            w = min(boxes[i, 2], boxes[j, 2]) - max(boxes[i, 0], boxes[j, 0])
            h = min(boxes[i, 3], boxes[j, 3]) - max(boxes[i, 1], boxes[j, 1])
            if w <= 0 or h <= 0:
                continue
            inter = w * h
            if inter / (area[i] + area[j] - inter) > iou:
                alive = False
                break
        if alive:
            keep[kept] = i
            kept += 1
    return keep[:kept]
