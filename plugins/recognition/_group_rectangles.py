"""Grouping the windows a cascade accepts into detections, as OpenCV's ``groupRectangles``:
windows partitioned by similarity, each group of enough neighbours averaged."""

from __future__ import annotations

import numpy as np

__all__ = [
    "group_rectangles",
]


def _partition(xywh: np.ndarray, eps: float) -> np.ndarray:
    """Class labels of boxes under the transitive closure of OpenCV's ``SimilarRects``:
    every side within ``eps`` · (mean of the smaller width and smaller height)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    count = len(xywh)
    x0, y0, w, h = xywh.T
    x1, y1 = x0 + w, y0 + h
    rows, cols = [], []
    for start in range(0, count, 1024):  # bounded memory: 1024 × N comparisons at a time
        part = slice(start, min(start + 1024, count))
        delta = (
            eps
            * 0.5
            * (np.minimum(w[part, None], w[None, :]) + np.minimum(h[part, None], h[None, :]))
        )
        close = (np.abs(x0[part, None] - x0[None, :]) <= delta) & (
            np.abs(y0[part, None] - y0[None, :]) <= delta
        )
        close &= np.abs(x1[part, None] - x1[None, :]) <= delta
        close &= np.abs(y1[part, None] - y1[None, :]) <= delta
        r, c = np.nonzero(close)
        rows.append(r + start)
        cols.append(c)
    graph = coo_matrix(
        (np.ones(sum(len(r) for r in rows)), (np.concatenate(rows), np.concatenate(cols))),
        shape=(count, count),
    )
    return connected_components(graph, directed=False)[1]


def group_rectangles(
    xyxy: np.ndarray, min_neighbours: int, eps: float
) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV's ``groupRectangles``: boxes (N, 4) fall into classes of similar boxes
    (:func:`_partition`), each class becomes its mean box, classes of at most
    ``min_neighbours`` boxes are dropped, and so is a class inside a clearly stronger
    one's box (grown by ``eps`` of its size: more than max(3, n) members, or the inner
    one has fewer than 3). Returns the boxes (M, 4) and their members (M,), strongest
    first. ``min_neighbours`` 0 returns the boxes as they are."""
    if len(xyxy) == 0:
        return np.zeros((0, 4)), np.zeros(0)
    if min_neighbours == 0:
        return xyxy.copy(), np.ones(len(xyxy))
    xywh = np.column_stack([xyxy[:, :2], xyxy[:, 2:] - xyxy[:, :2]])
    labels = _partition(xywh, eps)
    members = np.bincount(labels).astype(np.float64)
    means = (
        np.stack([np.bincount(labels, weights=xywh[:, i]) for i in range(4)], axis=1)
        / members[:, None]
    )
    strong = np.flatnonzero(members > min_neighbours)
    kept = []
    for i in strong:
        x, y, w, h = means[i]
        inside = False
        for j in strong:
            if j == i:
                continue
            bx, by, bw, bh = means[j]
            dx, dy = bw * eps, bh * eps
            if (
                x >= bx - dx
                and y >= by - dy
                and x + w <= bx + bw + dx
                and y + h <= by + bh + dy
                and (members[j] > max(3, members[i]) or members[i] < 3)
            ):
                inside = True
                break
        if not inside:
            kept.append(i)
    kept_array = np.array(kept, np.int64)
    order = kept_array[np.argsort(-members[kept_array], kind="stable")]
    boxes = means[order]
    return np.column_stack([boxes[:, :2], boxes[:, :2] + boxes[:, 2:]]), members[order]
