"""Scoring and drawing instance masks: COCO's mask average precision at one IoU, and a
picture of each detection's mask in its own colour."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import Array, ColorImage, Float, node

from ..shared.draw import colour_canvas
from ..shared.params import Count, Fraction
from ..synthetic._digit_scenes import Scenes, SceneSet
from ._draw import draw_rectangles
from ._mask import check_masks
from ._types import Detections, DetectionSet

__all__ = [
    "coco_average_precision",
    "draw_instances",
    "draw_true_instances",
    "mask_average_precision",
    "mask_iou",
]

RECALL_POINTS = np.linspace(0, 1, 101)
"""COCO's 101 recall thresholds."""
MAX_DETECTIONS = 100
"""COCO's maxDets: the best 100 detections per image are scored."""


def mask_iou(found: np.ndarray, truth: np.ndarray) -> np.ndarray:
    r"""IoU of every mask of ``found`` (N, H, W) with every mask of ``truth`` (M, H, W):
    :math:`|A \cap B| / |A \cup B|` (0 when both are empty)."""
    a = found.reshape(len(found), -1).astype(np.float32)
    b = truth.reshape(len(truth), -1).astype(np.float32)
    inter = a @ b.T
    union = a.sum(axis=1)[:, None] + b.sum(axis=1)[None, :] - inter
    return np.where(union > 0, inter / np.maximum(union, 1), 0.0)


def coco_average_precision(hit: np.ndarray, positives: int) -> float:
    """COCO's AP of detections sorted best first (``hit`` per detection): the precision
    envelope read at the 101 recall thresholds 0, 0.01, …, 1 (0 past the last recall)
    and averaged."""
    true_positives = np.cumsum(hit)
    recall = true_positives / positives
    precision = true_positives / np.arange(1, len(hit) + 1)
    envelope = np.maximum.accumulate(precision[::-1])[::-1] if len(hit) else precision
    where = np.searchsorted(recall, RECALL_POINTS, side="left")
    inside = where < len(envelope)
    return float(np.sum(envelope[where[inside]]) / len(RECALL_POINTS))


def _class_hits(
    detections: DetectionSet, masks: np.ndarray, scenes: SceneSet, truth: np.ndarray,
    label: int, iou: float,
) -> np.ndarray:  # fmt: skip
    """COCO matching within one class: detections best first (their first 100 per scene),
    each taking the unmatched true mask of its scene it overlaps most, at IoU ≥ ``iou``."""
    order = np.flatnonzero(detections.label == label)
    order = order[np.argsort(-detections.score[order], kind="stable")]
    hit = np.zeros(len(order), bool)
    taken = np.zeros(len(scenes.xyxy), bool)
    for scene in np.unique(detections.owner[order]):
        rows = np.flatnonzero(detections.owner[order] == scene)[:MAX_DETECTIONS]
        mine = np.flatnonzero((scenes.owner == scene) & (scenes.label == label))
        if len(mine) == 0:
            continue
        overlap = mask_iou(masks[order[rows]], truth[mine])
        for row, ious in zip(rows, overlap, strict=True):
            ious = np.where(taken[mine], -1.0, ious)
            best = int(np.argmax(ious))
            if ious[best] >= iou:
                taken[mine[best]] = True
                hit[row] = True
    ranked = np.zeros(len(order), bool)
    for scene in np.unique(detections.owner[order]):
        ranked[np.flatnonzero(detections.owner[order] == scene)[:MAX_DETECTIONS]] = True
    return hit[ranked]


@node("detection.mask_average_precision", version=1)
def mask_average_precision(
    detections: Detections,
    masks: Array,
    scenes: Scenes,
    truth: Array,
    *,
    iou: Annotated[float, Field(gt=0, le=1)] = 0.5,
) -> Float:
    r"""COCO's mask AP at one IoU (``mask_map50`` at 0.5): per class, detections best first
    (at most 100 per scene) each match the unmatched true instance of their class and
    scene whose mask they overlap most, when the mask IoU reaches ``iou``; the precision
    envelope :math:`\max_{r' \ge r} p(r')` is read at recalls 0, 0.01, …, 1 and averaged;
    the mean over the classes present in the scenes.

    Parameters
    ----------
    detections : Detections
        Scored, labelled detections over the scenes.
    masks : Array
        (D, H, W) bool, each detection's mask (``detection.predict_masks``).
    scenes : Scenes
        The scenes with their true boxes and classes.
    truth : Array
        (M, H, W) bool, the true mask of each true box.
    iou : float
        Mask overlap of a true positive.

    Returns
    -------
    float
        Mask AP in [0, 1].

    References
    ----------
    T.-Y. Lin et al., "Microsoft COCO: common objects in context", ECCV 2014; the COCO
    evaluation code (cocoeval.py, evaluateImg and accumulate).
    """
    check_masks(scenes, truth, "truth")
    if masks.shape != (len(detections), *scenes.images.shape[1:]):
        raise ValueError(
            f"masks must hold one mask per detection, shape "
            f"{(len(detections), *scenes.images.shape[1:])}; got {masks.shape}"
        )
    if detections.scenes != len(scenes):
        raise ValueError(
            f"the detections cover {detections.scenes} scenes but {len(scenes)} scenes are given"
        )
    classes = np.unique(scenes.label)
    if len(classes) == 0:
        raise ValueError("the scenes hold no true instance: mask AP is undefined")
    found, real = masks.astype(bool), truth.astype(bool)
    values = [
        coco_average_precision(
            _class_hits(detections, found, scenes, real, int(c), iou),
            int(np.sum(scenes.label == c)),
        )
        for c in classes
    ]
    return float(np.mean(values))


@node("detection.draw_instances", version=1)
def draw_instances(
    scenes: Scenes,
    detections: Detections,
    masks: Array,
    *,
    count: Count = 8,
    columns: Count = 4,
    min_score: Fraction = 0.5,
) -> ColorImage:
    """The first ``count`` scenes in a grid, each detection scoring at least ``min_score``
    drawn as its mask blended in its own colour (a seeded palette) with its box outlined
    in that colour.

    Parameters
    ----------
    scenes : Scenes
        The scenes.
    detections : Detections
        Detections over those scenes.
    masks : Array
        (D, H, W) bool, each detection's mask.
    count : int
        Scenes shown.
    columns : int
        Scenes per row.
    min_score : float
        Lowest score drawn.

    Returns
    -------
    ColorImage
        The grid, scenes two pixels apart.
    """
    if masks.shape != (len(detections), *scenes.images.shape[1:]):
        raise ValueError(f"masks must hold one scene-sized mask per detection, got {masks.shape}")
    palette = np.random.default_rng(0).uniform(0.25, 1.0, (max(len(detections), 1), 3))
    shown = min(count, len(scenes))
    height, width = scenes.images.shape[1:]
    rows = -(-shown // columns)
    canvas = np.ones((rows * (height + 2), min(shown, columns) * (width + 2), 3), np.float32)
    for scene in range(shown):
        picture = colour_canvas(scenes.images[scene])
        mine = np.flatnonzero((detections.owner == scene) & (detections.score >= min_score))
        for index in mine[::-1]:  # the best drawn last, on top
            colour = palette[index]
            picture[masks[index]] = 0.35 * picture[masks[index]] + 0.65 * colour
            draw_rectangles(picture, detections.xyxy[index : index + 1], tuple(colour), 1)
        r, c = divmod(scene, columns)
        top, left = r * (height + 2), c * (width + 2)
        canvas[top : top + height, left : left + width] = picture
    return canvas


@node("detection.draw_true_instances", version=1)
def draw_true_instances(
    scenes: Scenes, masks: Array, *, count: Count = 8, columns: Count = 4
) -> ColorImage:
    """The first ``count`` scenes in a grid with their true instances (e.g. of
    ``synthetic.instance_scenes``), each mask blended in its own colour and its box
    outlined, as ``detection.draw_instances`` draws detections.

    Parameters
    ----------
    scenes : Scenes
        Scenes with their true boxes.
    masks : Array
        (M, H, W) bool, the true mask of each true box.
    count : int
        Scenes shown.
    columns : int
        Scenes per row.

    Returns
    -------
    ColorImage
        The grid, scenes two pixels apart.
    """
    check_masks(scenes, masks)
    truth = DetectionSet(
        scenes.xyxy, np.ones(len(scenes.xyxy)), scenes.label, scenes.owner, len(scenes)
    )
    return draw_instances(scenes, truth, masks, count=count, columns=columns, min_score=0.0)
