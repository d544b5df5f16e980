"""Modern detection (seed: "Selective search", "A modern approach", "RCNN"): selective
search proposals, anchors, recall of proposals, ROI pooling, a detection head
(classification + box regression on pooled CNN features), class-wise non-maximum
suppression, mean average precision, and drawings of true and found boxes.

The box maths (IoU, NMS, the (tx, ty, tw, th) coding, anchors) is shared with the
recognition family in ``graphvision_plugins.shared.boxes``; the network is the ``cnn`` family's.
"""

from ._draw import draw_boxes, draw_rectangles, draw_scenes
from ._evaluate import (
    average_precision,
    match_detections,
    mean_average_precision,
    scene_recall,
    true_positive_iou,
)
from ._proposals import (
    anchors,
    check_scores,
    propose,
    recall,
    recall_at,
    recall_curve,
    region_boxes,
    selective_search,
)
from ._rcnn import (
    TrainingRois,
    class_wise_nms,
    detect,
    feature_extractor,
    feature_map,
    nms,
    roi_samples,
    scene_proposals,
    train_head,
    training_rois,
)
from ._roi import feature_rois, pool_rois, roi_pool
from ._rpn import (
    RegionProposer,
    RegionProposerModel,
    RegionProposerPort,
    cell_features,
    rpn_proposals,
    train_rpn,
)
from ._selective import hierarchical_grouping, selective_search_boxes
from ._types import (
    Detections,
    DetectionSet,
    DetectionsPort,
    Detector,
    DetectorModel,
    DetectorPort,
)

__all__ = [
    "DetectionSet",
    "Detections",
    "DetectionsPort",
    "Detector",
    "DetectorModel",
    "DetectorPort",
    "RegionProposer",
    "RegionProposerModel",
    "RegionProposerPort",
    "TrainingRois",
    "anchors",
    "average_precision",
    "cell_features",
    "check_scores",
    "class_wise_nms",
    "detect",
    "draw_boxes",
    "draw_rectangles",
    "draw_scenes",
    "feature_extractor",
    "feature_map",
    "feature_rois",
    "hierarchical_grouping",
    "match_detections",
    "mean_average_precision",
    "nms",
    "pool_rois",
    "propose",
    "recall",
    "recall_at",
    "recall_curve",
    "region_boxes",
    "roi_pool",
    "roi_samples",
    "rpn_proposals",
    "scene_proposals",
    "scene_recall",
    "selective_search",
    "selective_search_boxes",
    "train_head",
    "train_rpn",
    "training_rois",
    "true_positive_iou",
]
