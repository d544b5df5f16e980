"""R-CNN on scenes: proposals per scene, training ROIs, a Fast R-CNN head (ROI-pooled
features of a CNN's convolutional layers → classification and box regression), and
detection with class-wise non-maximum suppression (seed: "RCNN", "Fast RCNN ... ROI
pooling, classification and bounding box regression").

The backbone is a ``cnn.train`` network trained, as in R-CNN, on proposals cropped and
warped to a fixed size and labelled by their overlap with the true boxes (background
below IoU 0.3, the class of the true box at IoU 0.5 or more). Its convolutional layers
then run once over each whole scene (Fast R-CNN's shared computation); every proposal
is ROI-pooled from that feature map; a small fully connected head, trained by the same
SGD on pooled features, scores the classes and background; class-specific ridge
regressors on the same features move each box (R-CNN's appendix C).
"""

from __future__ import annotations

import json
from typing import Annotated, Any

import numpy as np
from pydantic import Field

from graphvision import node, one_blas_thread

from ..cnn import (
    Architecture,
    Network,
    NetworkModel,
    build_architecture,
    check_layer_texts,
    fit_network,
)
from ..shared.boxes import decode_boxes, encode_boxes, non_max_suppression
from ..shared.params import Count, Epochs, Fraction, Positive, Seed
from ..synthetic._digit_scenes import Scenes
from ._rcnn_rois import BACKGROUND, iou_order, training_rois
from ._roi import pool_rois
from ._types import Detections, DetectionSet, Detector, DetectorModel

__all__ = [
    "class_wise_nms",
    "detect",
    "feature_extractor",
    "feature_map",
    "nms",
    "train_head",
]


def feature_extractor(backbone: NetworkModel, layers: int) -> tuple[list[str], np.ndarray, int]:
    """The first ``layers`` layers of a trained network (convolution, ReLU and pooling
    only), their weights and their stride (the product of the pooling sizes)."""
    spec = json.loads(backbone.architecture)
    texts = list(spec["layers"])
    if not 1 <= layers < len(texts):
        raise ValueError(f"feature_layers must be in 1..{len(texts) - 1}, got {layers}")
    architecture = backbone.parsed()
    stride = 1
    for index, layer in enumerate(architecture.layers[:layers]):
        if layer.kind == "dense":
            raise ValueError(
                f"feature layer {index} '{texts[index]}' is fully connected; the feature map "
                "needs convolution, ReLU and pooling layers only"
            )
        stride *= layer.size if layer.kind == "maxpool" else 1
    pieces = [a.ravel() for params in architecture.split(backbone.weights)[:layers] for a in params]
    weights = np.concatenate(pieces) if pieces else np.zeros(0)
    return texts[:layers], weights, stride


def feature_map(layers: list[str], weights: np.ndarray, image: np.ndarray) -> np.ndarray:
    """The feature map (C, h, w) of the layers over a whole gray image (H, W)."""
    architecture: Architecture = build_architecture((1, *image.shape), layers)
    return architecture.forward(weights, image[None, None].astype(np.float64))[0][0]


def _pooled(
    layers: list[str], weights: np.ndarray, stride: int, pool: int, images: np.ndarray,
    owner: np.ndarray, xyxy: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """ROI-pooled features (R, C, pool, pool) of boxes over their scenes."""
    out = None
    with one_blas_thread():
        for scene in np.unique(owner):
            mine = np.flatnonzero(owner == scene)
            maps = feature_map(layers, weights, images[scene])
            pooled = pool_rois(maps, xyxy[mine], stride, pool)
            if out is None:
                out = np.zeros((len(xyxy), *pooled.shape[1:]))
            out[mine] = pooled
    return out if out is not None else np.zeros((0, 1, pool, pool))


def _ridge(features: np.ndarray, targets: np.ndarray, penalty: float) -> np.ndarray:
    r"""Least squares with an L2 penalty on all but the bias: (D + 1, 4), the bias last.

    The bias is left unpenalised by centring: :math:`w` solves the ridge problem on
    centred features and targets and :math:`b = \bar t - \bar x w`. With more
    features than regions (D > N) it is solved in the dual,
    :math:`w = X^T (X X^T + \lambda I)^{-1} T`, an N × N system instead of D × D
    (a pool of 40 cells made the D × D one 20 GB).
    """
    mean_x, mean_t = features.mean(axis=0), targets.mean(axis=0)
    x, t = features - mean_x, targets - mean_t
    count, width = x.shape
    if penalty == 0:
        weights = np.linalg.lstsq(x, t, rcond=None)[0]
    elif width <= count:
        weights = np.linalg.solve(x.T @ x + penalty * np.eye(width), x.T @ t)
    else:
        weights = x.T @ np.linalg.solve(x @ x.T + penalty * np.eye(count), t)
    return np.vstack([weights, mean_t - mean_x @ weights])


def _head_params(**params: Any) -> None:
    """The IoU thresholds in order (:func:`iou_order`) and each hidden layer a layer."""
    iou_order(**params)
    check_layer_texts(params["hidden"], "hidden")


@node("detection.train_head", version=1, check=_head_params)
def train_head(
    backbone: Network,
    scenes: Scenes,
    proposals: Detections,
    *,
    feature_layers: Count = 5,
    pool: Annotated[int, Field(ge=1, le=16)] = 4,
    hidden: list[str] = ["dense 64", "relu"],  # noqa: B006 (never mutated)
    epochs: Epochs = 30,
    batch_size: Count = 32,
    learning_rate: Positive = 0.02,
    momentum: Annotated[float, Field(ge=0, lt=1)] = 0.9,
    weight_decay: Annotated[float, Field(ge=0)] = 1e-4,
    ridge: Annotated[float, Field(ge=0)] = 10.0,
    positive_iou: Annotated[float, Field(gt=0, le=1)] = 0.5,
    negative_iou: Fraction = 0.3,
    jitter: Annotated[int, Field(ge=0, le=32)] = 4,
    negatives_per_positive: Positive = 2.0,
    seed: Seed = 0,
) -> Detector:
    """Train a Fast R-CNN head on ROI-pooled features of a backbone's first layers: a fully
    connected classifier of the classes and background (softmax cross-entropy, SGD with
    momentum) and one ridge box regressor per class on the same features.

    Regression targets are R-CNN's :math:`t = ((G_x - P_x)/P_w, (G_y - P_y)/P_h,
    \\log(G_w/P_w), \\log(G_h/P_h))`, fitted by :math:`W = (X^T X + \\lambda I)^{-1} X^T T`
    over the class's ROIs overlapping their true box by IoU ≥ ``positive_iou``.

    Parameters
    ----------
    backbone : Network
        A network trained on ROI crops (``cnn.train`` on ``detection.roi_samples``).
    scenes : Scenes
        Training scenes with their true boxes.
    proposals : Detections
        Proposals of those scenes.
    feature_layers : int
        How many of the backbone's first layers compute the feature map (convolution,
        ReLU and pooling only).
    pool : int
        ROI pooling cells per side (at most 16; Fast R-CNN uses 7): the head's input
        grows with its square.
    hidden : list of str
        The head's layers before its last (``dense K+1`` is appended), bounded as
        ``cnn.train``'s layers.
    epochs : int
        Passes over the training ROIs (at most 1,000).
    batch_size : int
        ROIs per gradient step.
    learning_rate : float
        Step size of the head's training.
    momentum : float
        Momentum of the head's training.
    weight_decay : float
        L2 penalty of the head's training.
    ridge : float
        L2 penalty λ of the box regressors.
    positive_iou : float
        Overlap from which a ROI takes the class of its true box.
    negative_iou : float
        Overlap below which a ROI is background.
    jitter : int
        Jittered copies of each true box added to the ROIs.
    negatives_per_positive : float
        Most background ROIs per object ROI.
    seed : int
        Seed of the ROI sampling and of the head's training.

    Returns
    -------
    Detector
        The backbone's feature layers, the head and the regressors.

    References
    ----------
    R. Girshick, "Fast R-CNN", ICCV 2015; R. Girshick et al., "Rich feature hierarchies
    for accurate object detection and semantic segmentation", CVPR 2014, appendix C.
    """
    layers, weights, stride = feature_extractor(backbone, feature_layers)
    rois = training_rois(
        scenes,
        proposals,
        positive_iou=positive_iou,
        negative_iou=negative_iou,
        jitter=jitter,
        negatives_per_positive=negatives_per_positive,
        seed=seed,
    )
    classes = np.unique(scenes.label)
    if len(classes) == 0 or not (rois.label >= 0).any():
        raise ValueError("the training scenes hold no object to learn from")
    features = _pooled(layers, weights, stride, pool, scenes.images, rois.owner, rois.xyxy)
    targets = np.searchsorted(np.concatenate([[BACKGROUND], classes]), rois.label)
    head_layers = [*hidden, f"dense {len(classes) + 1}"]
    head = build_architecture(features.shape[1:], head_layers)
    head_weights, history = fit_network(
        head,
        features,
        targets,
        epochs=epochs,
        batch_size=batch_size,
        learning_rate=learning_rate,
        momentum=momentum,
        weight_decay=weight_decay,
        seed=seed,
        what="detection.train_head",
    )
    flat = features.reshape(len(features), -1)
    regression = np.zeros((len(classes), flat.shape[1] + 1, 4))
    for k, label in enumerate(classes):
        mine = rois.label == label
        if mine.any():
            deltas = encode_boxes(rois.xyxy[mine], rois.target[mine])
            regression[k] = _ridge(flat[mine], deltas, ridge)
    spec = json.dumps({"input": list(features.shape[1:]), "layers": head_layers})
    return DetectorModel(
        json.dumps(layers), weights, stride, pool, spec, head_weights, classes, regression, history
    )


@node("detection.detect", version=1)
def detect(
    detector: Detector,
    scenes: Scenes,
    proposals: Detections,
    *,
    regression: bool = True,
    min_score: Fraction = 0.05,
) -> Detections:
    """Detect objects in scenes: pool each proposal from the scene's feature map, score the
    classes (softmax), keep the best non-background class when its probability reaches
    ``min_score``, and move the box by that class's regressor (``detection.nms`` then
    suppresses overlaps class by class). A scene without proposals gives no detection.

    Parameters
    ----------
    detector : Detector
        A trained detector (``detection.train_head``).
    scenes : Scenes
        Scenes to search.
    proposals : Detections
        Proposals of those scenes.
    regression : bool
        Apply the box regressors (False: keep the proposals' boxes).
    min_score : float
        Lowest class probability kept.

    Returns
    -------
    Detections
        Boxes with class probability and class, scene by scene, before suppression.
    """
    if proposals.scenes != len(scenes):
        raise ValueError(
            f"the proposals cover {proposals.scenes} scenes but {len(scenes)} scenes are given"
        )
    layers = json.loads(detector.feature_layers)
    spec = json.loads(detector.head_architecture)
    head = build_architecture(tuple(spec["input"]), spec["layers"])
    height, width = scenes.images.shape[1:]
    found = []
    for scene in np.unique(proposals.owner):
        mine = np.flatnonzero(proposals.owner == scene)
        boxes = proposals.xyxy[mine]
        features = _pooled(
            layers, detector.feature_weights, detector.stride, detector.pool,
            scenes.images, proposals.owner[mine], boxes,
        )  # fmt: skip
        scores = head.forward(detector.head_weights, features)[0]
        probability = np.exp(scores - scores.max(axis=1, keepdims=True))
        probability /= probability.sum(axis=1, keepdims=True)
        best = probability[:, 1:].argmax(axis=1)
        score = probability[np.arange(len(best)), best + 1]
        keep = score >= min_score
        boxes, best, score = boxes[keep], best[keep], score[keep]
        if regression and len(boxes):
            flat = np.hstack([features[keep].reshape(len(boxes), -1), np.ones((len(boxes), 1))])
            deltas = np.einsum("nd,ndk->nk", flat, detector.regression[best])
            boxes = decode_boxes(boxes, deltas)
            boxes[:, [0, 2]] = np.clip(boxes[:, [0, 2]], 0, width)
            boxes[:, [1, 3]] = np.clip(boxes[:, [1, 3]], 0, height)
            sound = (boxes[:, 2] - boxes[:, 0] > 0.5) & (boxes[:, 3] - boxes[:, 1] > 0.5)
            boxes, best, score = boxes[sound], best[sound], score[sound]
        found.append((boxes, score, detector.classes[best], np.full(len(boxes), scene)))
    if not found:
        empty = np.zeros(0, np.int64)
        return DetectionSet(np.zeros((0, 4)), np.zeros(0), empty, empty.copy(), len(scenes))
    return DetectionSet(
        np.concatenate([f[0] for f in found]).reshape(-1, 4),
        np.concatenate([f[1] for f in found]),
        np.concatenate([f[2] for f in found]).astype(np.int64),
        np.concatenate([f[3] for f in found]).astype(np.int64),
        len(scenes),
    )


def class_wise_nms(detections: DetectionSet, iou: float) -> DetectionSet:
    """Greedy NMS within each (scene, class); the result scene by scene, best first."""
    keep = []
    groups = np.unique(np.column_stack([detections.owner, detections.label]), axis=0)
    for owner, label in groups:
        same = np.flatnonzero((detections.owner == owner) & (detections.label == label))
        keep.append(same[non_max_suppression(detections.xyxy[same], detections.score[same], iou)])
    kept = np.concatenate(keep) if keep else np.zeros(0, np.int64)
    order = np.lexsort((-detections.score[kept], detections.owner[kept]))
    return detections.take(kept[order])


@node("detection.nms", version=1)
def nms(detections: Detections, *, iou: Fraction = 0.3) -> Detections:
    """Class-wise non-maximum suppression: within each scene and class, keep the best
    detection and drop those overlapping it by IoU above ``iou``, repeat.

    Parameters
    ----------
    detections : Detections
        Scored, labelled boxes over scenes.
    iou : float
        Overlap above which the weaker detection of the same class and scene goes.

    Returns
    -------
    Detections
        The kept detections, scene by scene, best first.
    """
    return class_wise_nms(detections, iou)
