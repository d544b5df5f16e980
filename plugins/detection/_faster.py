"""Faster R-CNN (seed: "faster RCNN, which consists of feature extraction, region proposal
network RPN, ROI pooling, classification and bounding box regression"): training the RPN
and the Fast R-CNN head together with the backbone's last layers, and detecting with the
RPN's proposals."""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Annotated, Any, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import node, one_blas_thread

from ..cnn import Network, check_layer_texts
from ..shared.boxes import anchor_boxes, decode_boxes
from ..shared.params import Count, Epochs, Fraction, Positive, Seed
from ..synthetic._digit_scenes import Scenes
from ._faster_train import DELTA_SCALE, Settings, build_nets, initial, propose_boxes, train_joint
from ._faster_types import FasterRcnn, FasterRcnnModel
from ._proposals import PositiveList
from ._rcnn import feature_extractor
from ._rcnn_rois import iou_order
from ._rpn import check_anchors_fit
from ._types import Detections, DetectionSet

__all__ = ["FasterRcnnResult", "faster_rcnn", "scene_outputs", "train_faster_rcnn"]


def _faster_params(**params: Any) -> None:
    """IoU thresholds in order, at least one fine-tuned layer, hidden layers parse."""
    iou_order(**params)
    if params["frozen_layers"] >= params["feature_layers"]:
        raise ValueError(
            f"frozen_layers ({params['frozen_layers']}) must be below feature_layers "
            f"({params['feature_layers']}): at least one backbone layer is fine-tuned"
        )
    check_layer_texts(params["hidden"], "hidden")


def _frozen_maps(layers: list[str], weights: np.ndarray, images: np.ndarray) -> np.ndarray:
    """The frozen layers' maps of all scenes (N, C, h, w) float32 (the scenes themselves
    when no layer is frozen)."""
    from ..cnn import build_architecture

    stack = images[:, None].astype(np.float32)
    if not layers:
        return stack
    architecture = build_architecture((1, *images.shape[1:]), layers)
    parts = [architecture.forward(weights, stack[i : i + 32])[0] for i in range(0, len(stack), 32)]
    return np.concatenate(parts).astype(np.float32)


@node("detection.train_faster_rcnn", version=1, check=_faster_params)
def train_faster_rcnn(
    backbone: Network,
    scenes: Scenes,
    *,
    feature_layers: Count = 5,
    frozen_layers: Annotated[int, Field(ge=0)] = 3,
    sizes: PositiveList = [16.0, 22.0, 30.0],  # noqa: B006
    ratios: PositiveList = [0.7, 1.0, 1.5, 2.2],  # noqa: B006
    rpn_channels: Annotated[int, Field(ge=1, le=512)] = 32,
    pool: Annotated[int, Field(ge=1, le=16)] = 4,
    hidden: list[str] = ["dense 128", "relu"],  # noqa: B006
    positive_iou: Annotated[float, Field(gt=0, le=1)] = 0.7,
    negative_iou: Fraction = 0.3,
    anchor_batch: Annotated[int, Field(ge=2, le=4096)] = 128,
    roi_batch: Annotated[int, Field(ge=2, le=1024)] = 64,
    train_proposals: Annotated[int, Field(ge=1, le=2000)] = 150,
    epochs: Epochs = 10,
    learning_rate: Positive = 0.01,
    momentum: Annotated[float, Field(ge=0, lt=1)] = 0.9,
    weight_decay: Annotated[float, Field(ge=0)] = 1e-4,
    seed: Seed = 0,
) -> FasterRcnn:
    r"""Train a Faster R-CNN approximately jointly: per scene, one SGD step on the sum of
    the region proposal network's loss and the Fast R-CNN head's loss, whose gradients
    both reach the backbone's fine-tuned layers (Ren et al., section 3.2, "approximate
    joint training"; the proposals' coordinates are not differentiated).

    .. math::
        L = L_{cls}^{rpn} + L_{reg}^{rpn} + L_{cls}^{head} + L_{reg}^{head}

    Anchors: IoU ≥ ``positive_iou`` with a true box (or a true box's best anchor) are
    objects, below ``negative_iou`` background; ``anchor_batch`` sampled per scene, at
    most half objects. ROIs: the RPN's ``train_proposals`` best proposals after NMS at 0.7
    and the true boxes, ``roi_batch`` sampled, at most a quarter objects (IoU ≥ 0.5).
    Box codings (R-CNN's :math:`t_x, t_y, t_w, t_h`) are divided by (0.1, 0.1, 0.2, 0.2).

    Parameters
    ----------
    backbone : Network
        A trained network (e.g. ``cnn.train`` on ``detection.roi_samples``) whose first
        ``feature_layers`` layers (convolution, ReLU, pooling) make the feature map.
    scenes : Scenes
        Training scenes with their true boxes.
    feature_layers : int
        The backbone's layers making the shared feature map.
    frozen_layers : int
        The first layers kept as trained; the others up to ``feature_layers`` are fine-tuned.
    sizes, ratios : list of float
        Anchor sides (pixels) and aspect ratios h / w (A = sizes × ratios shapes).
    rpn_channels : int
        Filters of the RPN's 3 × 3 convolution.
    pool : int
        ROI pooling cells per side.
    hidden : list of str
        The head's layers before its last (``dense 5K+1`` is appended).
    positive_iou, negative_iou : float
        Anchor labelling thresholds (0.7 and 0.3 in the paper).
    anchor_batch, roi_batch : int
        Anchors and ROIs sampled per scene (256 and 128 in the paper).
    train_proposals : int
        Proposals kept per scene during training.
    epochs : int
        Passes over the scenes.
    learning_rate, momentum, weight_decay : float
        SGD with momentum.
    seed : int
        Seed of the initial weights, the scene order and the samples.

    Returns
    -------
    FasterRcnn
        The fine-tuned feature layers, the RPN and the head.

    References
    ----------
    S. Ren, K. He, R. Girshick and J. Sun, "Faster R-CNN: towards real-time object
    detection with region proposal networks", NeurIPS 2015.
    """
    check_anchors_fit(sizes, ratios, scenes.images.shape[1:])
    classes = np.unique(scenes.label)
    if len(classes) == 0:
        raise ValueError("the training scenes hold no object to learn from")
    layers, weights, stride = feature_extractor(backbone, feature_layers)
    frozen_count = sum(
        int(np.prod(s)) for p in backbone.parsed().parameter_shapes[:frozen_layers] for s in p
    )
    frozen_maps = _frozen_maps(layers[:frozen_layers], weights[:frozen_count], scenes.images)
    nets = build_nets(
        layers[frozen_layers:], frozen_maps.shape[1:], stride, pool, rpn_channels,
        len(sizes) * len(ratios), list(hidden), len(classes),
    )  # fmt: skip
    rows, cols = nets.tuned.shapes[-1][1:]
    anchors = anchor_boxes(rows, cols, stride, tuple(sizes), tuple(ratios))
    settings = Settings(
        positive_iou, negative_iou, anchor_batch, roi_batch, 0.25, train_proposals, epochs,
        learning_rate, momentum, weight_decay, seed,
    )  # fmt: skip
    with one_blas_thread():
        trained, history = train_joint(
            nets, frozen_maps, [weights[frozen_count:], *initial(nets, seed)], scenes, classes,
            anchors, settings,
        )  # fmt: skip
    head = {
        "input": list(nets.head.shapes[0]),
        "layers": [*hidden, f"dense {5 * len(classes) + 1}"],
    }
    return FasterRcnnModel(
        json.dumps(layers), np.concatenate([weights[:frozen_count], trained[0]]), frozen_layers,
        stride, pool, json.dumps({"sizes": list(sizes), "ratios": list(ratios)}),
        json.dumps([f"conv {rpn_channels}x3", "relu", f"conv {5 * nets.shapes}x1"]), trained[1],
        json.dumps(head), trained[2], classes.astype(np.int64), history,
    )  # fmt: skip


class FasterRcnnResult(NamedTuple):
    detections: Detections
    proposals: Detections


def scene_outputs(
    model: FasterRcnnModel, image: np.ndarray, proposals: int, nms: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One scene through the network: the feature map (C, h, w), the proposals and their
    objectness, and the head's outputs (R, 5K + 1) for the proposals."""
    from ._faster_kernels import roi_max_pool_argmax
    from ._roi import feature_rois

    features_net, rpn_net, head_net = model.architectures(image.shape)
    maps = features_net.forward(model.feature_weights, image[None, None].astype(np.float32))[0]
    out = rpn_net.forward(model.rpn_weights, maps)[0][0]
    rows, cols = maps.shape[2:]
    shapes = model.shapes()
    anchors = anchor_boxes(
        rows, cols, model.stride, tuple(shapes["sizes"]), tuple(shapes["ratios"])
    )
    count = len(shapes["sizes"]) * len(shapes["ratios"])
    boxes, objectness = propose_boxes(
        out, anchors, count, image.shape, 4 * proposals, proposals, nms
    )
    feature = np.ascontiguousarray(maps[0])
    pooled, _ = roi_max_pool_argmax(
        feature, feature_rois(boxes, model.stride, feature.shape[1:]), model.pool
    )
    scores = head_net.forward(model.head_weights, pooled.astype(np.float32))[0]
    return feature, boxes, objectness, scores.astype(np.float64)


def _classified(
    model: FasterRcnnModel, boxes: np.ndarray, scores: np.ndarray, image_shape: tuple[int, ...],
    min_score: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Every (proposal, class) whose softmax probability reaches ``min_score``, its box moved
    by that class's regressor and clipped: boxes, probabilities, class labels."""
    classes = len(model.classes)
    logits = scores[:, : classes + 1]
    probability = np.exp(logits - logits.max(axis=1, keepdims=True))
    probability /= probability.sum(axis=1, keepdims=True)
    roi, k = np.nonzero(probability[:, 1:] >= min_score)
    deltas = scores[roi[:, None], classes + 1 + 4 * k[:, None] + np.arange(4)] * DELTA_SCALE
    moved = decode_boxes(boxes[roi], deltas).reshape(-1, 4)
    height, width = image_shape
    moved[:, [0, 2]] = np.clip(moved[:, [0, 2]], 0, width)
    moved[:, [1, 3]] = np.clip(moved[:, [1, 3]], 0, height)
    sound = (moved[:, 2] - moved[:, 0] > 0.5) & (moved[:, 3] - moved[:, 1] > 0.5)
    return moved[sound], probability[roi, k + 1][sound], model.classes[k][sound]


def _joined(pieces: Sequence[tuple[np.ndarray, ...]], scenes: int) -> DetectionSet:
    if not pieces:
        empty = np.zeros(0, np.int64)
        return DetectionSet(np.zeros((0, 4)), np.zeros(0), empty, empty.copy(), scenes)
    return DetectionSet(
        np.concatenate([p[0] for p in pieces]).reshape(-1, 4),
        np.concatenate([p[1] for p in pieces]).astype(np.float64),
        np.concatenate([p[2] for p in pieces]).astype(np.int64),
        np.concatenate([p[3] for p in pieces]).astype(np.int64),
        scenes,
    )


@node("detection.faster_rcnn", version=1)
def faster_rcnn(
    model: FasterRcnn,
    scenes: Scenes,
    *,
    proposals: Annotated[int, Field(ge=1, le=2000)] = 300,
    nms: Fraction = 0.7,
    min_score: Fraction = 0.05,
) -> FasterRcnnResult:
    """Detect with a trained Faster R-CNN: per scene, one pass of the feature layers, the
    RPN's proposals (anchors moved by their codings, the 4 × ``proposals`` best by
    objectness, NMS at ``nms``, the ``proposals`` best kept), each ROI-pooled and scored by
    the head; every class whose probability reaches ``min_score`` gives a detection moved
    by its own regressor, :math:`G = (P_x + P_w t_x, P_y + P_h t_y, P_w e^{t_w}, P_h
    e^{t_h})` (``detection.nms`` then suppresses overlaps class by class).

    Parameters
    ----------
    model : FasterRcnn
        A trained Faster R-CNN (``detection.train_faster_rcnn``).
    scenes : Scenes
        Gray scenes (their true boxes are not used).
    proposals : int
        Proposals per scene (300 in the paper).
    nms : float
        IoU above which the weaker of two proposals goes.
    min_score : float
        Lowest class probability kept.

    Returns
    -------
    detections : Detections
        Labelled, scored boxes before class-wise suppression.
    proposals : Detections
        The RPN's proposals (label -1), each scene's best first.

    References
    ----------
    S. Ren, K. He, R. Girshick and J. Sun, "Faster R-CNN: towards real-time object
    detection with region proposal networks", NeurIPS 2015.
    """
    found, proposed = [], []
    with one_blas_thread():
        for scene, image in enumerate(scenes.images):
            _, boxes, objectness, scores = scene_outputs(model, image, proposals, nms)
            owner = np.full(len(boxes), scene)
            proposed.append((boxes, objectness, np.full(len(boxes), -1), owner))
            moved, score, label = _classified(model, boxes, scores, image.shape, min_score)
            found.append((moved, score, label, np.full(len(moved), scene)))
    return FasterRcnnResult(_joined(found, len(scenes)), _joined(proposed, len(scenes)))
