"""Areas and overlaps of the quadrilaterals that instances are (polygon IoU for the
suppression of overlapping instances and for scoring against the truth)."""

from __future__ import annotations

import numpy as np

__all__ = [
    "convex_overlap",
    "polygon_area",
    "quad_iou",
]


def polygon_area(points: np.ndarray) -> float:
    r"""Signed area of a polygon ``(N, 2)`` by the shoelace formula,
    :math:`\tfrac12 \sum_i (x_i y_{i+1} - x_{i+1} y_i)` (positive when its vertices turn
    from +x towards +y, clockwise on the screen).

    >>> polygon_area(np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float))
    2.0
    """
    if len(points) < 3:
        return 0.0
    x, y = points[:, 0], points[:, 1]
    return float(0.5 * (x @ np.roll(y, -1) - np.roll(x, -1) @ y))


def _is_convex(quad: np.ndarray) -> bool:
    """Every turn of the closed polygon has the same, non-zero sign."""
    edges = np.roll(quad, -1, axis=0) - quad
    turns = (
        edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1]
        - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
    )
    return bool((turns > 0).all() or (turns < 0).all())


def _inside_convex(polygon: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Which ``points`` (N, 2) lie inside the convex ``polygon`` (on the same side of every
    edge)."""
    edges = np.roll(polygon, -1, axis=0) - polygon
    relative = points[:, None, :] - polygon[None, :, :]
    cross = edges[None, :, 0] * relative[:, :, 1] - edges[None, :, 1] * relative[:, :, 0]
    return (cross >= 0).all(axis=1) | (cross <= 0).all(axis=1)


def convex_overlap(a: np.ndarray, b: np.ndarray) -> float:
    """Area of the intersection of two convex polygons (Sutherland-Hodgman clipping of
    ``a`` by each edge of ``b``); either orientation.

    >>> square = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], float)
    >>> convex_overlap(square, square + 1)
    1.0
    """
    if polygon_area(a) < 0:
        a = a[::-1]
    if polygon_area(b) < 0:
        b = b[::-1]
    out = [p for p in a]
    for start, end in zip(b, np.roll(b, -1, axis=0), strict=True):
        if not out:
            break
        edge = end - start

        def side(p: np.ndarray, start: np.ndarray = start, edge: np.ndarray = edge) -> float:
            return float(edge[0] * (p[1] - start[1]) - edge[1] * (p[0] - start[0]))

        clipped = []
        for i, p in enumerate(out):
            q = out[i - 1]
            sp, sq = side(p), side(q)
            if sp >= 0:
                if sq < 0:
                    clipped.append(q + (p - q) * (sq / (sq - sp)))
                clipped.append(p)
            elif sq >= 0:
                clipped.append(q + (p - q) * (sq / (sq - sp)))
        out = clipped
    return abs(polygon_area(np.array(out))) if len(out) >= 3 else 0.0


def quad_iou(a: np.ndarray, b: np.ndarray) -> float:
    r"""Intersection over union of two convex quadrilaterals,
    :math:`|a \cap b| / (|a| + |b| - |a \cap b|)`."""
    inter = convex_overlap(a, b)
    union = abs(polygon_area(a)) + abs(polygon_area(b)) - inter
    return inter / union if union > 0 else 0.0
