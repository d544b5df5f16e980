"""Box maths shared by the recognition and detection families: intersection over union,
greedy non-maximum suppression, the box-regression parametrisation and anchors.

Boxes are ``(x0, y0, x1, y1)`` rows (x the column, y the row, in pixels) with
``x0 < x1`` and ``y0 < y1``; the width is ``x1 - x0`` (a box covering pixel
columns 3..5 inclusive is ``(3, y0, 6, y1)``).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "anchor_boxes",
    "check_boxes",
    "decode_boxes",
    "encode_boxes",
    "iou_matrix",
    "non_max_suppression",
]


def check_boxes(xyxy: np.ndarray, what: str = "box") -> np.ndarray:
    """``xyxy`` as a float64 (N, 4) array, or ValueError naming ``what``, the first bad row
    and why (not 4 columns, not finite, negative or zero width or height)."""
    boxes = np.asarray(xyxy, np.float64)
    if boxes.ndim != 2 or boxes.shape[1] != 4:
        raise ValueError(f"{what}es must be an (N, 4) array of (x0, y0, x1, y1), got {boxes.shape}")
    finite = np.isfinite(boxes).all(axis=1)
    if not finite.all():
        row = int(np.flatnonzero(~finite)[0])
        raise ValueError(f"{what} row {row} is not finite: {boxes[row].tolist()}")
    empty = (boxes[:, 2] <= boxes[:, 0]) | (boxes[:, 3] <= boxes[:, 1])
    if empty.any():
        row = int(np.flatnonzero(empty)[0])
        x0, y0, x1, y1 = boxes[row]
        raise ValueError(
            f"{what} row {row} has width {x1 - x0:g} and height {y1 - y0:g}; "
            "both must be positive (x0 < x1, y0 < y1)"
        )
    return boxes


def iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    r"""Intersection over union of every box of ``a`` (N, 4) with every box of ``b`` (M, 4).

    .. math:: \mathrm{IoU}(A, B) = \frac{|A \cap B|}{|A| + |B| - |A \cap B|}

    Returns
    -------
    (N, M) float64 in [0, 1]
    """
    low = np.maximum(a[:, None, :2], b[None, :, :2])
    high = np.minimum(a[:, None, 2:], b[None, :, 2:])
    inter = np.prod(np.clip(high - low, 0, None), axis=2)
    area_a = np.prod(a[:, 2:] - a[:, :2], axis=1)
    area_b = np.prod(b[:, 2:] - b[:, :2], axis=1)
    return inter / (area_a[:, None] + area_b[None, :] - inter)


def non_max_suppression(boxes: np.ndarray, scores: np.ndarray, iou: float) -> np.ndarray:
    """Indices of the boxes kept by greedy NMS: the best remaining box is kept and every box
    overlapping it by more than ``iou`` is dropped, until none remain (best first; ties keep
    the earlier box). NaN scores are refused."""
    if np.isnan(scores).any():
        row = int(np.flatnonzero(np.isnan(scores))[0])
        raise ValueError(f"box scores must not be NaN (row {row} is)")
    order = np.argsort(-scores, kind="stable")
    keep = []
    while len(order):
        best = order[0]
        keep.append(best)
        overlap = iou_matrix(boxes[best : best + 1], boxes[order[1:]])[0]
        order = order[1:][overlap <= iou]
    return np.array(keep, np.int64)


def _centre_size(xyxy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    width = xyxy[:, 2] - xyxy[:, 0]
    height = xyxy[:, 3] - xyxy[:, 1]
    return xyxy[:, 0] + width / 2, xyxy[:, 1] + height / 2, width, height


def encode_boxes(proposals: np.ndarray, targets: np.ndarray) -> np.ndarray:
    r"""The regression targets that move each proposal P onto its target box G (R-CNN):

    .. math::
        t_x = (G_x - P_x) / P_w,\quad t_y = (G_y - P_y) / P_h,\quad
        t_w = \log(G_w / P_w),\quad t_h = \log(G_h / P_h)

    with (x, y) the box centre and (w, h) its size.

    Returns
    -------
    (N, 4) float64 rows (tx, ty, tw, th)

    References
    ----------
    R. Girshick et al., "Rich feature hierarchies for accurate object detection and semantic
    segmentation", CVPR 2014, appendix C.
    """
    px, py, pw, ph = _centre_size(proposals)
    gx, gy, gw, gh = _centre_size(targets)
    return np.column_stack([(gx - px) / pw, (gy - py) / ph, np.log(gw / pw), np.log(gh / ph)])


def decode_boxes(proposals: np.ndarray, deltas: np.ndarray) -> np.ndarray:
    r"""The inverse of :func:`encode_boxes`: the boxes that ``deltas`` (N, 4) move the
    proposals onto, :math:`G_x = P_x + P_w t_x`, :math:`G_w = P_w e^{t_w}` (and the same in y).

    Returns
    -------
    (N, 4) float64 boxes (x0, y0, x1, y1)
    """
    px, py, pw, ph = _centre_size(proposals)
    gx = px + pw * deltas[:, 0]
    gy = py + ph * deltas[:, 1]
    gw = pw * np.exp(deltas[:, 2])
    gh = ph * np.exp(deltas[:, 3])
    return np.column_stack([gx - gw / 2, gy - gh / 2, gx + gw / 2, gy + gh / 2])


def anchor_boxes(
    rows: int, cols: int, stride: float, sizes: tuple[float, ...], ratios: tuple[float, ...]
) -> np.ndarray:
    r"""Faster R-CNN's anchors: at the centre of every cell of a ``rows`` × ``cols`` feature
    map with ``stride`` pixels per cell, one box per size s and aspect ratio r = h / w, of
    area s² (:math:`w = s / \sqrt{r}`, :math:`h = s \sqrt{r}`).

    Returns
    -------
    (rows · cols · len(sizes) · len(ratios), 4) float64, cell by cell in row-major order,
    sizes outer and ratios inner within a cell.

    References
    ----------
    S. Ren et al., "Faster R-CNN: towards real-time object detection with region proposal
    networks", NeurIPS 2015, section 3.1.1.
    """
    size = np.repeat(np.asarray(sizes, np.float64), len(ratios))
    ratio = np.tile(np.asarray(ratios, np.float64), len(sizes))
    half_w = size / np.sqrt(ratio) / 2
    half_h = size * np.sqrt(ratio) / 2
    shapes = np.column_stack([-half_w, -half_h, half_w, half_h])
    cy, cx = np.mgrid[0:rows, 0:cols].astype(np.float64)
    centres = (np.column_stack([cx.ravel(), cy.ravel()]) + 0.5) * stride
    shifts = np.tile(centres, (1, 2))
    return (shifts[:, None, :] + shapes[None, :, :]).reshape(-1, 4)
