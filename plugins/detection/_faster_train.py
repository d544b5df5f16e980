"""Faster R-CNN's approximately joint training in NumPy (Ren et al. 2015, section 3.2): one
SGD step per training scene adds the region proposal network's loss and the Fast R-CNN
head's loss, and both gradients flow into the fine-tuned backbone layers they share.

Per step, on one scene: the shared feature map ``F`` (frozen first layers, then the
fine-tuned ones); the RPN (a 3 × 3 convolution and a 1 × 1 convolution giving, per anchor
shape, one objectness logit and four box deltas) scored on a seeded sample of anchors;
proposals from the RPN's current output (not differentiated through, which makes the
training "approximately joint"), the true boxes added; a seeded sample of ROIs ROI-pooled
from ``F`` and scored by the head (softmax over the classes and background, and one box
regressor per class). The losses are

.. math::
    L = \\frac{1}{N_a}\\sum_i \\ell_{bce}(o_i, p^*_i)
        + \\frac{1}{N_a}\\sum_i p^*_i\\, \\mathrm{smooth}_{L_1}(t_i - t^*_i)
        + \\frac{1}{N_r}\\sum_j \\ell_{ce}(s_j, c^*_j)
        + \\frac{1}{N_r}\\sum_j [c^*_j > 0]\\, \\mathrm{smooth}_{L_1}(u_j^{c^*_j} - v_j)

with the box codings divided by (0.1, 0.1, 0.2, 0.2) as the authors' code does.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..cnn import Architecture, build_architecture, initial_weights, softmax_cross_entropy
from ..shared.boxes import decode_boxes, encode_boxes, iou_matrix
from ._roi import feature_rois

__all__ = [
    "DELTA_SCALE",
    "JointNets",
    "Settings",
    "anchor_labels",
    "anchor_targets",
    "propose_boxes",
    "roi_targets",
    "smooth_l1",
    "train_joint",
]

DELTA_SCALE = np.array([0.1, 0.1, 0.2, 0.2])
"""Box codings are divided by these before regression (the authors' code)."""


@dataclass(frozen=True)
class Settings:
    """Training settings of :func:`train_joint` (see ``detection.train_faster_rcnn``)."""

    positive_iou: float = 0.7
    negative_iou: float = 0.3
    anchor_batch: int = 128
    roi_batch: int = 64
    roi_positive_fraction: float = 0.25
    train_proposals: int = 150
    epochs: int = 10
    learning_rate: float = 0.01
    momentum: float = 0.9
    weight_decay: float = 1e-4
    seed: int = 0


@dataclass(frozen=True)
class JointNets:
    """The three trained parts: the fine-tuned feature layers (on the frozen map), the RPN
    (on the feature map) and the head (on the pooled ROIs)."""

    tuned: Architecture
    rpn: Architecture
    head: Architecture
    stride: int
    pool: int
    shapes: int  # anchor shapes A


def with_input_gradient(architecture: Architecture) -> Architecture:
    """The same architecture whose first layer also computes its input's gradient."""
    layers = list(architecture.layers)
    layers[0] = dataclasses.replace(layers[0], input_gradient=True)
    return dataclasses.replace(architecture, layers=layers)


def backward_with_input(
    architecture: Architecture, weights: np.ndarray, grad: np.ndarray, saved: list[Any]
) -> tuple[np.ndarray, np.ndarray]:
    """The gradients with respect to the input and to the (flat) weights."""
    params = architecture.split(weights)
    pieces: list[list[np.ndarray]] = []
    for layer, memo, layer_params in zip(
        reversed(architecture.layers), reversed(saved), reversed(params), strict=True
    ):
        grad, d_params = layer.backward(grad, memo, layer_params)
        pieces.append(d_params)
    flat = [d.ravel() for d_params in reversed(pieces) for d in d_params]
    return grad, (np.concatenate(flat) if flat else np.zeros(0, grad.dtype))


def smooth_l1(x: np.ndarray, t: np.ndarray) -> tuple[float, np.ndarray]:
    r"""Sum of :math:`\mathrm{smooth}_{L_1}(d) = d^2/2` for :math:`|d| < 1`, else
    :math:`|d| - 1/2`, over :math:`d = x - t`, and its gradient with respect to ``x``."""
    d = x - t
    a = np.abs(d)
    return float(np.where(a < 1, 0.5 * d * d, a - 0.5).sum()), np.clip(d, -1, 1)


def anchor_labels(
    anchors: np.ndarray, truth: np.ndarray, settings: Settings
) -> tuple[np.ndarray, np.ndarray]:
    """Each anchor's label (1 object: IoU ≥ ``positive_iou`` with a true box, or a true
    box's best anchor; 0 background: IoU < ``negative_iou`` with every one; -1 neither) and
    the index of its best true box (int8 and int64)."""
    if len(truth) == 0:
        return np.zeros(len(anchors), np.int8), np.zeros(len(anchors), np.int64)
    overlap = iou_matrix(anchors, truth)
    best = overlap.max(axis=1)
    label = np.full(len(anchors), -1, np.int8)
    label[best < settings.negative_iou] = 0
    label[best >= settings.positive_iou] = 1
    label[overlap.argmax(axis=0)] = 1
    return label, overlap.argmax(axis=1)


def anchor_targets(
    anchors: np.ndarray, truth: np.ndarray, labelled: tuple[np.ndarray, np.ndarray],
    rng: np.random.Generator, settings: Settings,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """A seeded sample of at most ``anchor_batch`` anchors (half objects at most) of their
    labels ``labelled`` (:func:`anchor_labels`): their indices, labels, and the scaled
    codings of the objects' true boxes (zero for background)."""
    label, match = labelled
    positive = rng.permutation(np.flatnonzero(label == 1))[: settings.anchor_batch // 2]
    negative = rng.permutation(np.flatnonzero(label == 0))
    negative = negative[: settings.anchor_batch - len(positive)]
    index = np.concatenate([positive, negative])
    deltas = np.zeros((len(index), 4))
    if len(positive):
        chosen = anchors[positive]
        deltas[: len(positive)] = encode_boxes(chosen, truth[match[positive]]) / DELTA_SCALE
    return index, label[index].astype(np.int64), deltas


def rpn_outputs(out: np.ndarray, shapes: int) -> tuple[np.ndarray, np.ndarray]:
    """The RPN's output map (5A, h, w) as per-anchor logits (h·w·A,) and scaled codings
    (h·w·A, 4), cell by cell, shapes inner (the order of ``anchor_boxes``)."""
    rows, cols = out.shape[1:]
    logits = out[:shapes].transpose(1, 2, 0).reshape(-1)
    deltas = out[shapes:].reshape(shapes, 4, rows, cols).transpose(2, 3, 0, 1).reshape(-1, 4)
    return logits, deltas


def rpn_gradient(
    out: np.ndarray, shapes: int, index: np.ndarray, label: np.ndarray, target: np.ndarray
) -> tuple[float, np.ndarray]:
    """The RPN loss over the sampled anchors (logistic objectness plus smooth L1 on the
    objects' codings, both divided by the sample size) and its gradient, shaped as ``out``."""
    logits, deltas = rpn_outputs(out, shapes)
    count = max(len(index), 1)
    z = logits[index]
    p = 1 / (1 + np.exp(-z))
    loss = float(np.sum(np.logaddexp(0, z) - label * z)) / count
    g_logits = np.zeros_like(logits)
    g_logits[index] = (p - label) / count
    g_deltas = np.zeros_like(deltas)
    objects = index[label == 1]
    reg_loss, g = smooth_l1(deltas[objects], target[label == 1])
    g_deltas[objects] = g / count
    rows, cols = out.shape[1:]
    grad = np.empty_like(out)
    grad[:shapes] = g_logits.reshape(rows, cols, shapes).transpose(2, 0, 1)
    grad[shapes:] = (
        g_deltas.reshape(rows, cols, shapes, 4)
        .transpose(2, 3, 0, 1)
        .reshape(4 * shapes, rows, cols)
    )
    return loss + reg_loss / count, grad


def propose_boxes(
    out: np.ndarray, anchors: np.ndarray, shapes: int, image_shape: tuple[int, int],
    pre_nms: int, post_nms: int, nms: float,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Proposals from the RPN's output: anchors moved by their codings, clipped to the
    scene, boxes under 2 px dropped, the ``pre_nms`` best by objectness, non-maximum
    suppression at ``nms``, the ``post_nms`` best kept; boxes and objectness."""
    logits, deltas = rpn_outputs(out, shapes)
    height, width = image_shape
    boxes = decode_boxes(anchors, deltas.astype(np.float64) * DELTA_SCALE)
    boxes[:, [0, 2]] = np.clip(boxes[:, [0, 2]], 0, width)
    boxes[:, [1, 3]] = np.clip(boxes[:, [1, 3]], 0, height)
    score = 1 / (1 + np.exp(-logits.astype(np.float64)))
    sound = (boxes[:, 2] - boxes[:, 0] >= 2) & (boxes[:, 3] - boxes[:, 1] >= 2)
    boxes, score = boxes[sound], score[sound]
    from ._faster_kernels import greedy_nms

    if len(score) > pre_nms:
        best = np.argpartition(-score, pre_nms - 1)[:pre_nms]
        score_order = np.argsort(-score[best], kind="stable")
        top = best[score_order]
    else:
        top = np.argsort(-score, kind="stable")
    kept = top[greedy_nms(np.ascontiguousarray(boxes[top]), nms, post_nms)]
    return boxes[kept], score[kept]


def roi_targets(
    proposals: np.ndarray, truth: np.ndarray, classes: np.ndarray, rng: np.random.Generator,
    settings: Settings,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """A seeded sample of ``roi_batch`` ROIs among the proposals and the true boxes (at most
    ``roi_positive_fraction`` objects: IoU ≥ 0.5; background below 0.5): boxes, class
    index (0 background, k + 1 the k-th class) and the scaled codings of the objects."""
    boxes = np.concatenate([proposals, truth]) if len(truth) else proposals
    target = np.zeros(len(boxes), np.int64)
    deltas = np.zeros((len(boxes), 4))
    if len(truth):
        overlap = iou_matrix(boxes, truth)
        best = overlap.argmax(axis=1)
        hit = overlap.max(axis=1) >= 0.5
        target[hit] = classes[best[hit]] + 1
        deltas = encode_boxes(boxes, truth[best]) / DELTA_SCALE
    most = int(settings.roi_batch * settings.roi_positive_fraction)
    positive = rng.permutation(np.flatnonzero(target > 0))[:most]
    negative = rng.permutation(np.flatnonzero(target == 0))
    index = np.concatenate([positive, negative[: settings.roi_batch - len(positive)]])
    return boxes[index], target[index], deltas[index]


def head_gradient(
    scores: np.ndarray, target: np.ndarray, deltas: np.ndarray, classes: int
) -> tuple[float, np.ndarray]:
    """The head loss (cross-entropy of the K + 1 scores, smooth L1 on the objects' codings
    of their own class, divided by the number of ROIs) and its gradient."""
    loss, g_cls = softmax_cross_entropy(scores[:, : classes + 1], target)
    grad = np.zeros_like(scores)
    grad[:, : classes + 1] = g_cls
    objects = np.flatnonzero(target > 0)
    columns = classes + 1 + 4 * (target[objects, None] - 1) + np.arange(4)
    reg_loss, g = smooth_l1(scores[objects[:, None], columns], deltas[objects])
    grad[objects[:, None], columns] = g / len(scores)
    return loss + reg_loss / len(scores), grad


def build_nets(
    tuned_layers: list[str], frozen_shape: tuple[int, ...], stride: int, pool: int,
    rpn_channels: int, shapes: int, hidden: list[str], classes: int,
) -> JointNets:  # fmt: skip
    """The architectures of the fine-tuned layers, the RPN and the head."""
    tuned = build_architecture(frozen_shape, tuned_layers)
    channels = tuned.shapes[-1][0]
    rpn = build_architecture(
        tuned.shapes[-1], [f"conv {rpn_channels}x3", "relu", f"conv {5 * shapes}x1"]
    )
    head = build_architecture((channels, pool, pool), [*hidden, f"dense {5 * classes + 1}"])
    return JointNets(
        tuned, with_input_gradient(rpn), with_input_gradient(head), stride, pool, shapes
    )


def initial(nets: JointNets, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """He-initialised RPN and head weights, their last layers scaled by 0.1 (small first
    objectness and codings)."""
    pieces = []
    for offset, architecture in enumerate((nets.rpn, nets.head)):
        weights = initial_weights(architecture, seed + offset + 1)
        last = sum(int(np.prod(s)) for s in architecture.parameter_shapes[-1])
        weights[-last:] *= 0.1
        pieces.append(weights)
    return pieces[0], pieces[1]


def train_joint(
    nets: JointNets,
    frozen_maps: np.ndarray,
    weights: list[np.ndarray],
    scenes: Any,
    classes: np.ndarray,
    anchors: np.ndarray,
    settings: Settings,
) -> tuple[list[np.ndarray], np.ndarray]:
    """SGD with momentum over the scenes (one scene per step, a seeded order each epoch) on
    the joint loss; the tuned, RPN and head weights (float64) and the mean loss per epoch.
    ValueError naming the learning rate when the loss is not finite."""
    rng = np.random.default_rng(settings.seed)
    params = [np.asarray(w, np.float32) for w in weights]
    velocity = [np.zeros_like(w) for w in params]
    labelled = [anchor_labels(anchors, scenes.boxes_of(s)[0], settings) for s in range(len(scenes))]
    history = []
    for epoch in range(settings.epochs):
        losses = []
        for scene in rng.permutation(len(frozen_maps)):
            truth, labels = scenes.boxes_of(int(scene))
            loss, grads = joint_step(
                nets, params, frozen_maps[scene : scene + 1], truth,
                np.searchsorted(classes, labels), anchors, labelled[scene], scenes.images.shape[1:],
                rng, settings,
            )  # fmt: skip
            if not np.isfinite(loss):
                raise ValueError(
                    f"detection.train_faster_rcnn: the loss diverged at epoch {epoch + 1} with "
                    f"learning_rate={settings.learning_rate:g}; lower the learning rate"
                )
            for w, v, g in zip(params, velocity, grads, strict=True):
                v *= settings.momentum
                v -= settings.learning_rate * (g + settings.weight_decay * w)
                w += v
            losses.append(loss)
        history.append(float(np.mean(losses)))
    return [w.astype(np.float64) for w in params], np.array(history)


def joint_step(
    nets: JointNets, params: list[np.ndarray], frozen: np.ndarray, truth: np.ndarray,
    classes: np.ndarray, anchors: np.ndarray, labelled: tuple[np.ndarray, np.ndarray],
    image_shape: tuple[int, int], rng: np.random.Generator, settings: Settings,
) -> tuple[float, list[np.ndarray]]:  # fmt: skip
    """The joint loss of one scene and its gradients with respect to the tuned, RPN and
    head weights (see the module)."""
    from ._faster_kernels import roi_max_pool_argmax

    tuned_w, rpn_w, head_w = params
    features, saved_tuned = nets.tuned.forward(tuned_w, frozen, keep=True)
    out, saved_rpn = nets.rpn.forward(rpn_w, features, keep=True)
    index, label, target = anchor_targets(anchors, truth, labelled, rng, settings)
    rpn_loss, g_out = rpn_gradient(out[0], nets.shapes, index, label, target)
    proposals, _ = propose_boxes(
        out[0], anchors, nets.shapes, image_shape, 4 * settings.train_proposals,
        settings.train_proposals, 0.7,
    )  # fmt: skip
    boxes, cls, deltas = roi_targets(proposals, truth, classes, rng, settings)
    feature = np.ascontiguousarray(features[0])
    rois = feature_rois(boxes, nets.stride, feature.shape[1:])
    pooled, where = roi_max_pool_argmax(feature, rois, nets.pool)
    scores, saved_head = nets.head.forward(head_w, pooled.astype(np.float32), keep=True)
    head_loss, g_scores = head_gradient(scores, cls, deltas, (scores.shape[1] - 1) // 5)
    g_pooled, d_head = backward_with_input(
        nets.head, head_w, g_scores.astype(np.float32), saved_head
    )
    g_features = np.zeros(feature.size, np.float32)
    np.add.at(g_features, where.ravel(), g_pooled.ravel())
    g_rpn_in, d_rpn = backward_with_input(
        nets.rpn, rpn_w, g_out[None].astype(np.float32), saved_rpn
    )
    g_features = g_features.reshape(features.shape) + g_rpn_in
    d_tuned = nets.tuned.backward(tuned_w, g_features, saved_tuned)
    return rpn_loss + head_loss, [d_tuned, d_rpn, d_head]
