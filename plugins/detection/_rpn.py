"""A region proposal network on anchors (Faster R-CNN, seed: "RPN is a small neural network
that slides over the feature map and predicts region proposals and objectness scores. It
uses anchor boxes to generate proposals").

At every cell of a backbone's feature map (the first layers of a ``cnn.train`` network,
as for ``detection.train_head``) the features of the 3 × 3 cells around it are one
vector; for each anchor shape (size × aspect ratio) a softmax regression scores
objectness and a ridge regressor moves the anchor (R-CNN's box coding). Anchors
overlapping a true box by IoU ≥ ``positive_iou`` (and the best anchor of each true box)
are objects, those below ``negative_iou`` background. Proposals are the best-scored
moved anchors after non-maximum suppression.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from pydantic import Field

from graphvision import PortValueError, RecordPort, node, one_blas_thread

from ..cnn import Network, build_architecture, fit_network
from ..shared.boxes import anchor_boxes, decode_boxes, encode_boxes, iou_matrix, non_max_suppression
from ..shared.params import Count, Epochs, Fraction, Positive, Seed
from ..synthetic._digit_scenes import Scenes
from ._proposals import PositiveList
from ._rcnn import feature_extractor, feature_map
from ._rcnn_rois import iou_order
from ._types import Detections, DetectionSet

__all__ = [
    "RegionProposer",
    "RegionProposerModel",
    "RegionProposerPort",
    "cell_features",
    "check_anchors_fit",
    "rpn_proposals",
    "train_rpn",
]


@dataclass(frozen=True, eq=False)
class RegionProposerModel:
    """The backbone's feature layers (JSON) and weights, the stride, the anchor shapes
    (JSON ``{"sizes": [...], "ratios": [...]}``), and per shape the objectness weights
    ``objectness`` (A, D + 1, 2) and the box regressors ``regression`` (A, D + 1, 4)."""

    feature_layers: str
    feature_weights: np.ndarray
    stride: int
    anchors: str
    objectness: np.ndarray
    regression: np.ndarray


class RegionProposerPort(RecordPort):
    """A :class:`RegionProposerModel` with finite float64 weights, one objectness scorer and
    one regressor per anchor shape."""

    value_class = RegionProposerModel

    @classmethod
    def validate(cls, value: Any) -> RegionProposerModel:
        value = super().validate(value)
        for name in ("feature_weights", "objectness", "regression"):
            array = getattr(value, name)
            if not isinstance(array, np.ndarray) or array.dtype != np.float64:
                raise PortValueError(f"RegionProposer '{name}' must be float64")
            if not np.isfinite(array).all():
                raise PortValueError(f"RegionProposer '{name}' must be finite")
        shapes = json.loads(value.anchors)
        count = len(shapes["sizes"]) * len(shapes["ratios"])
        if value.objectness.shape[::2] != (count, 2) or value.regression.shape[::2] != (count, 4):
            raise PortValueError(
                f"RegionProposer needs one scorer and regressor per {count} shapes"
            )
        return value

    @classmethod
    def summary(cls, value: RegionProposerModel) -> str:
        return f"RegionProposer {value.objectness.shape[0]} anchor shapes"


RegionProposer = Annotated[RegionProposerModel, RegionProposerPort]


def cell_features(maps: np.ndarray) -> np.ndarray:
    """The features of the 3 × 3 cells around every cell of a map (C, h, w), zero beyond
    its border: (h·w, 9·C), row-major over the cells."""
    padded = np.pad(maps, ((0, 0), (1, 1), (1, 1)))
    windows = sliding_window_view(padded, (3, 3), axis=(1, 2))  # (C, h, w, 3, 3)
    channels, rows, cols = maps.shape
    return windows.transpose(1, 2, 0, 3, 4).reshape(rows * cols, channels * 9)


def check_anchors_fit(
    sizes: list[float], ratios: list[float], image_shape: tuple[int, ...]
) -> None:
    r"""ValueError naming the anchor size and ratio whose box (:math:`w = s / \sqrt{r}`,
    :math:`h = s \sqrt{r}`) is larger than the scenes in both directions: such an anchor
    overlaps every true box by little more than the box's share of the scene, so none of
    its anchors can be an object and its objectness cannot be learned."""
    height, width = image_shape[:2]
    for size in sizes:
        for ratio in ratios:
            w, h = size / np.sqrt(ratio), size * np.sqrt(ratio)
            if w > width and h > height:
                raise ValueError(
                    f"anchor size {size:g} with ratio {ratio:g} is a {w:.0f}×{h:.0f} box, "
                    f"larger than the {width}×{height} scenes: give sizes smaller than the scenes"
                )


def _scene_anchors(maps: np.ndarray, stride: int, shapes: dict) -> np.ndarray:
    rows, cols = maps.shape[1:]
    boxes = anchor_boxes(rows, cols, stride, tuple(shapes["sizes"]), tuple(shapes["ratios"]))
    return boxes.reshape(rows * cols, -1, 4)


def _anchor_labels(
    flat: np.ndarray, truth: np.ndarray, positive_iou: float, negative_iou: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The anchors' IoU with the true boxes, which are positive (at least ``positive_iou``,
    or the best anchor of a true box) and which negative (below ``negative_iou``)."""
    overlap = iou_matrix(flat, truth) if len(truth) else np.zeros((len(flat), 0))
    best_iou = overlap.max(axis=1) if len(truth) else np.zeros(len(flat))
    positive = best_iou >= positive_iou
    if len(truth):
        positive[overlap.argmax(axis=0)] = True  # every true box has an anchor
    negative = best_iou < negative_iou
    return overlap, positive, negative


def _train_scorers(
    positives: list[list[np.ndarray]],
    negatives: list[list[np.ndarray]],
    deltas: list[list[np.ndarray]],
    dims: int,
    epochs: int,
    learning_rate: float,
    ridge: float,
    seed: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Per anchor shape its objectness scorer (a dense layer, weights then bias) trained on
    its positives and negatives, and its box regressor (ridge) on the positives' deltas."""
    from ._rcnn import _ridge

    count = len(positives)
    objectness = np.zeros((count, dims + 1, 2))
    regression = np.zeros((count, dims + 1, 4))
    scorer = build_architecture((dims,), ["dense 2"])
    for a in range(count):
        pos, neg = np.concatenate(positives[a]), np.concatenate(negatives[a])
        if len(pos) == 0:
            continue
        x = np.concatenate([pos, neg])
        y = np.concatenate([np.ones(len(pos), np.int64), np.zeros(len(neg), np.int64)])
        trained, _ = fit_network(
            scorer, x, y, epochs=epochs, batch_size=64, learning_rate=learning_rate,
            momentum=0.9, weight_decay=1e-4, seed=seed + a, what="detection.train_rpn",
        )  # fmt: skip
        objectness[a] = np.vstack([trained[: 2 * dims].reshape(dims, 2), trained[2 * dims :]])
        regression[a] = _ridge(pos, np.concatenate(deltas[a]), ridge)
    return objectness, regression


@node("detection.train_rpn", version=1, check=iou_order)
def train_rpn(
    backbone: Network,
    scenes: Scenes,
    *,
    feature_layers: Count = 5,
    sizes: PositiveList = [16.0, 24.0, 32.0],  # noqa: B006
    ratios: PositiveList = [0.7, 1.0, 1.4],  # noqa: B006
    positive_iou: Annotated[float, Field(gt=0, le=1)] = 0.5,
    negative_iou: Fraction = 0.3,
    negatives_per_positive: Positive = 3.0,
    epochs: Epochs = 8,
    learning_rate: Positive = 0.02,
    ridge: Annotated[float, Field(ge=0)] = 10.0,
    seed: Seed = 0,
) -> RegionProposer:
    """Train a region proposal network over a backbone's feature map: per anchor shape, a
    softmax regression of objectness on the 3 × 3 cell features and a ridge regressor of
    the box coding (tx, ty, tw, th) towards the true box.

    Parameters
    ----------
    backbone : Network
        A network whose first layers compute the feature map.
    scenes : Scenes
        Training scenes with their true boxes.
    feature_layers : int
        How many of the backbone's first layers compute the feature map.
    sizes : list of float
        Anchor sides (pixels); an anchor larger than the scenes is refused.
    ratios : list of float
        Anchor aspect ratios h / w.
    positive_iou : float
        Anchors overlapping a true box this much are objects (so is each box's best).
    negative_iou : float
        Anchors below this overlap with every true box are background.
    negatives_per_positive : float
        Most background anchors per object anchor (a seeded subset) of each shape.
    epochs : int
        Passes of the objectness training (at most 1,000).
    learning_rate : float
        Step size of the objectness training.
    ridge : float
        L2 penalty of the box regressors.
    seed : int
        Seed of the background subset and of the training.

    Returns
    -------
    RegionProposer
        The feature layers, anchors, objectness scorers and regressors.

    References
    ----------
    S. Ren et al., "Faster R-CNN: towards real-time object detection with region proposal
    networks", NeurIPS 2015, section 3.1.
    """
    check_anchors_fit(sizes, ratios, scenes.images.shape[1:])
    layers, weights, stride = feature_extractor(backbone, feature_layers)
    shapes = {"sizes": list(sizes), "ratios": list(ratios)}
    count = len(sizes) * len(ratios)
    rng = np.random.default_rng(seed)
    positives: list[list[np.ndarray]] = [[] for _ in range(count)]
    negatives: list[list[np.ndarray]] = [[] for _ in range(count)]
    deltas: list[list[np.ndarray]] = [[] for _ in range(count)]
    with one_blas_thread():
        for scene in range(len(scenes)):
            truth, _ = scenes.boxes_of(scene)
            maps = feature_map(layers, weights, scenes.images[scene])
            features = cell_features(maps)
            anchors = _scene_anchors(maps, stride, shapes)
            flat = anchors.reshape(-1, 4)
            overlap, positive, negative = _anchor_labels(flat, truth, positive_iou, negative_iou)
            for a in range(count):
                index = np.arange(a, len(flat), count)
                cells = index // count
                hit = index[positive[index]]
                positives[a].append(features[hit // count])
                if len(hit):
                    match = truth[overlap[hit].argmax(axis=1)]
                    deltas[a].append(encode_boxes(flat[hit], match))
                miss = cells[negative[index]]
                keep = max(int(negatives_per_positive * max(len(hit), 1)), 1)
                negatives[a].append(features[rng.permutation(miss)[:keep]])
    dims = features.shape[1] if len(scenes) else 0
    objectness, regression = _train_scorers(
        positives, negatives, deltas, dims, epochs, learning_rate, ridge, seed
    )
    return RegionProposerModel(
        json.dumps(layers), weights, stride, json.dumps(shapes), objectness, regression
    )


def _apply(design: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Every anchor shape's linear map (A, D + 1, K) applied to every cell's features
    (N, D + 1) in one matrix product: (N, A·K), shape by shape."""
    shapes, dims, outputs = weights.shape
    return design @ weights.transpose(1, 0, 2).reshape(dims, shapes * outputs)


@node("detection.rpn_proposals", version=1)
def rpn_proposals(
    rpn: RegionProposer,
    scenes: Scenes,
    *,
    max_boxes: Count = 50,
    nms: Fraction = 0.7,
) -> Detections:
    """Proposals of a region proposal network: every anchor moved by its regressor, scored
    by its objectness, clipped to the scene; the best ``max_boxes`` per scene after
    non-maximum suppression at ``nms``.

    Parameters
    ----------
    rpn : RegionProposer
        A trained region proposal network (``detection.train_rpn``).
    scenes : Scenes
        Scenes to propose boxes in.
    max_boxes : int
        Proposals per scene.
    nms : float
        IoU above which the weaker of two proposals goes.

    Returns
    -------
    Detections
        Proposals (label -1) with their objectness, scene by scene, best first.
    """
    layers = json.loads(rpn.feature_layers)
    shapes = json.loads(rpn.anchors)
    height, width = scenes.images.shape[1:]
    pieces = []
    with one_blas_thread():
        for scene in range(len(scenes)):
            maps = feature_map(layers, rpn.feature_weights, scenes.images[scene])
            features = cell_features(maps)
            design = np.hstack([features, np.ones((len(features), 1))])
            anchors = _scene_anchors(maps, rpn.stride, shapes)
            shapes_count = len(rpn.objectness)
            logits = _apply(design, rpn.objectness).reshape(len(design), shapes_count, 2)
            score = 1 / (1 + np.exp(logits[..., 0] - logits[..., 1]))  # softmax of 2
            moves = _apply(design, rpn.regression)
            boxes = decode_boxes(anchors.reshape(-1, 4), moves.reshape(-1, 4))
            boxes[:, [0, 2]] = np.clip(boxes[:, [0, 2]], 0, width)
            boxes[:, [1, 3]] = np.clip(boxes[:, [1, 3]], 0, height)
            score = score.ravel()
            sound = (boxes[:, 2] - boxes[:, 0] >= 2) & (boxes[:, 3] - boxes[:, 1] >= 2)
            boxes, score = boxes[sound], score[sound]
            top = np.argsort(-score, kind="stable")[: 20 * max_boxes]
            kept = top[non_max_suppression(boxes[top], score[top], nms)][:max_boxes]
            pieces.append((boxes[kept], score[kept], np.full(len(kept), scene, np.int64)))
    xyxy = np.concatenate([p[0] for p in pieces]).reshape(-1, 4) if pieces else np.zeros((0, 4))
    score = np.concatenate([p[1] for p in pieces]) if pieces else np.zeros(0)
    owner = np.concatenate([p[2] for p in pieces]) if pieces else np.zeros(0, np.int64)
    return DetectionSet(xyxy, score, np.full(len(xyxy), -1, np.int64), owner, len(scenes))
