"""Scoring detections against true boxes: PASCAL VOC average precision and the mean IoU of
true positives."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import Float, node

from ..shared.boxes import iou_matrix
from ..synthetic._digit_scenes import Scenes, SceneSet
from ._types import Detections, DetectionSet

__all__ = [
    "average_precision",
    "match_detections",
    "mean_average_precision",
    "scene_recall",
    "true_positive_iou",
]


def match_detections(
    detections: DetectionSet, scenes: SceneSet, iou: float
) -> tuple[np.ndarray, np.ndarray]:
    """For each detection (taken in decreasing score within its class): whether it is a true
    positive, i.e. overlaps by IoU ≥ ``iou`` a true box of its class and scene that no
    better-scored detection took; and that IoU (0 for false positives)."""
    hit = np.zeros(len(detections), bool)
    overlap = np.zeros(len(detections))
    if detections.scenes != len(scenes):
        raise ValueError(
            f"the detections cover {detections.scenes} scenes but {len(scenes)} scenes are given"
        )
    taken = np.zeros(len(scenes.xyxy), bool)
    for index in np.argsort(-detections.score, kind="stable"):
        same = np.flatnonzero(
            (scenes.owner == detections.owner[index]) & (scenes.label == detections.label[index])
        )
        if len(same) == 0:
            continue
        ious = iou_matrix(detections.xyxy[index : index + 1], scenes.xyxy[same])[0]
        ious[taken[same]] = -1
        best = int(np.argmax(ious))
        if ious[best] >= iou:
            taken[same[best]] = True
            hit[index] = True
            overlap[index] = ious[best]
    return hit, overlap


def average_precision(scores: np.ndarray, hit: np.ndarray, positives: int) -> float:
    r"""Area under the precision–recall curve with precision made monotone (VOC 2010 on,
    all points): :math:`AP = \sum_n (r_n - r_{n-1}) \max_{m \ge n} p_m`."""
    if positives == 0:
        return float("nan")
    order = np.argsort(-scores, kind="stable")
    true_positives = np.cumsum(hit[order])
    recall = np.concatenate([[0.0], true_positives / positives])
    precision = true_positives / np.arange(1, len(order) + 1)
    envelope = np.maximum.accumulate(precision[::-1])[::-1]
    return float(np.sum(np.diff(recall) * envelope))


@node("detection.mean_average_precision", version=1)
def mean_average_precision(
    detections: Detections, scenes: Scenes, *, iou: Annotated[float, Field(gt=0, le=1)] = 0.5
) -> Float:
    """Mean over the classes present in the scenes of the average precision of the
    detections (PASCAL VOC: a detection is a true positive when it overlaps an unclaimed
    true box of its class by IoU ≥ ``iou``; all-point interpolation).

    Parameters
    ----------
    detections : Detections
        Scored, labelled boxes over the scenes.
    scenes : Scenes
        The scenes with their true boxes.
    iou : float
        Overlap of a true positive (0.5: mAP@0.5).

    Returns
    -------
    float
        mAP in [0, 1].

    References
    ----------
    M. Everingham et al., "The PASCAL visual object classes (VOC) challenge", IJCV 88(2),
    2010.
    """
    hit, _ = match_detections(detections, scenes, iou)
    classes = np.unique(scenes.label)
    if len(classes) == 0:
        raise ValueError("the scenes hold no true box: mAP is undefined")
    values = [
        average_precision(
            detections.score[detections.label == c],
            hit[detections.label == c],
            int(np.sum(scenes.label == c)),
        )
        for c in classes
    ]
    return float(np.mean(values))


@node("detection.true_positive_iou", version=1)
def true_positive_iou(
    detections: Detections, scenes: Scenes, *, iou: Annotated[float, Field(gt=0, le=1)] = 0.5
) -> Float:
    """The mean IoU of the true positives with their true boxes: how well the found boxes
    fit (what box regression improves).

    Parameters
    ----------
    detections : Detections
        Scored, labelled boxes over the scenes.
    scenes : Scenes
        The scenes with their true boxes.
    iou : float
        Overlap of a true positive.

    Returns
    -------
    float
        Mean IoU in [iou, 1] (NaN without true positives).
    """
    hit, overlap = match_detections(detections, scenes, iou)
    return float(overlap[hit].mean()) if hit.any() else float("nan")


@node("detection.scene_recall", version=1)
def scene_recall(
    proposals: Detections,
    scenes: Scenes,
    *,
    count: Annotated[int, Field(ge=0)] = 0,
    iou: Annotated[float, Field(gt=0, le=1)] = 0.5,
) -> Float:
    """The fraction of all true boxes that one of the first ``count`` proposals of their
    scene (in the proposals' order) overlaps by IoU ≥ ``iou``.

    Parameters
    ----------
    proposals : Detections
        Proposals of the scenes, each scene's best first.
    scenes : Scenes
        The scenes with their true boxes.
    count : int
        Proposals per scene taken (0: all).
    iou : float
        Overlap that counts as found.

    Returns
    -------
    float
        Recall in [0, 1].
    """
    if proposals.scenes != len(scenes):
        raise ValueError(
            f"the proposals cover {proposals.scenes} scenes but {len(scenes)} scenes are given"
        )
    if len(scenes.xyxy) == 0:
        raise ValueError("the scenes hold no true box: recall is undefined")
    found = 0
    for scene in range(len(scenes)):
        truth, _ = scenes.boxes_of(scene)
        mine = proposals.xyxy[proposals.owner == scene]
        mine = mine[:count] if count else mine
        if len(truth) and len(mine):
            found += int((iou_matrix(truth, mine).max(axis=1) >= iou).sum())
    return found / len(scenes.xyxy)
