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
from ._faster import FasterRcnnResult, faster_rcnn, train_faster_rcnn
from ._faster_draw import draw_proposals, faster_rcnn_loss
from ._faster_types import FasterRcnn, FasterRcnnModel, FasterRcnnPort
from ._mask import mask_inputs, predict_masks, train_mask_head
from ._mask_eval import (
    coco_average_precision,
    draw_instances,
    draw_true_instances,
    mask_average_precision,
    mask_iou,
)
from ._mask_head import MaskHead, MaskHeadModel, MaskHeadPort, mask_targets, paste_mask, roi_align
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
from ._rcnn import class_wise_nms, detect, feature_extractor, feature_map, nms, train_head
from ._rcnn_rois import TrainingRois, roi_samples, scene_proposals, training_rois
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
from ._types import Detections, DetectionSet, DetectionsPort, Detector, DetectorModel, DetectorPort

__all__ = [
    "DetectionSet",
    "Detections",
    "DetectionsPort",
    "Detector",
    "DetectorModel",
    "DetectorPort",
    "FasterRcnn",
    "FasterRcnnModel",
    "FasterRcnnPort",
    "FasterRcnnResult",
    "MaskHead",
    "MaskHeadModel",
    "MaskHeadPort",
    "RegionProposer",
    "RegionProposerModel",
    "RegionProposerPort",
    "TrainingRois",
    "anchors",
    "average_precision",
    "cell_features",
    "check_scores",
    "class_wise_nms",
    "coco_average_precision",
    "detect",
    "draw_boxes",
    "draw_instances",
    "draw_proposals",
    "draw_rectangles",
    "draw_scenes",
    "draw_true_instances",
    "faster_rcnn",
    "faster_rcnn_loss",
    "feature_extractor",
    "feature_map",
    "feature_rois",
    "hierarchical_grouping",
    "mask_average_precision",
    "mask_inputs",
    "mask_iou",
    "mask_targets",
    "match_detections",
    "mean_average_precision",
    "nms",
    "paste_mask",
    "pool_rois",
    "predict_masks",
    "propose",
    "recall",
    "recall_at",
    "recall_curve",
    "region_boxes",
    "roi_align",
    "roi_pool",
    "roi_samples",
    "rpn_proposals",
    "scene_proposals",
    "scene_recall",
    "selective_search",
    "selective_search_boxes",
    "train_faster_rcnn",
    "train_head",
    "train_mask_head",
    "train_rpn",
    "training_rois",
    "true_positive_iou",
]
