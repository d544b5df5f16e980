"""Modern detection (seed: "Selective search", "A modern approach", "RCNN"): selective
search proposals, anchors, recall of proposals, ROI pooling, a detection head
(classification + box regression on pooled CNN features), class-wise non-maximum
suppression, mean average precision, and drawings of true and found boxes.

The box maths (IoU, NMS, the (tx, ty, tw, th) coding, anchors) is shared with the
recognition family in ``graphvision_plugins._boxes``; the network is the ``cnn`` family's.
"""

from ._draw import draw_boxes, draw_rectangles
from ._proposals import (
    anchors,
    check_scores,
    recall,
    recall_at,
    recall_curve,
    region_boxes,
    selective_search,
)
from ._selective import hierarchical_grouping, selective_search_boxes

__all__ = [
    "anchors",
    "check_scores",
    "draw_boxes",
    "draw_rectangles",
    "hierarchical_grouping",
    "recall",
    "recall_at",
    "recall_curve",
    "region_boxes",
    "selective_search",
    "selective_search_boxes",
]
