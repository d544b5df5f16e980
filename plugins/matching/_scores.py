"""Found instances scored against the scenes' true instances (polygon IoU): the node
``matching.score_instances``."""

from __future__ import annotations

import math
from typing import Annotated, NamedTuple

import numpy as np
from pydantic import Field

from graphvision import Float, Int, node

from ..synthetic import ObjectScenes, ObjectSceneSet
from ._instances import Instances, InstanceSet
from ._polygons import quad_iou

__all__ = [
    "match_instances",
    "score_instances",
]


def match_instances(instances: InstanceSet, scenes: ObjectSceneSet, iou: float) -> np.ndarray:
    """For each found instance, the index of the true instance it finds, or -1: taken in
    decreasing inlier count, each takes the untaken true instance of its scene that it
    overlaps most, if their polygon IoU (:func:`quad_iou`) is at least ``iou``."""
    if instances.scenes != len(scenes):
        raise ValueError(
            f"the instances were found in {instances.scenes} scenes but {len(scenes)} scenes "
            "are given"
        )
    found = np.full(len(instances), -1, np.int64)
    taken = np.zeros(len(scenes.owner), bool)
    for index in np.argsort(-instances.inliers, kind="stable"):
        candidates = np.flatnonzero((scenes.owner == instances.owner[index]) & ~taken)
        if len(candidates) == 0:
            continue
        overlaps = [quad_iou(instances.quads[index], scenes.quads[j]) for j in candidates]
        best = int(np.argmax(overlaps))
        if overlaps[best] >= iou:
            found[index] = candidates[best]
            taken[candidates[best]] = True
    return found


class InstanceScores(NamedTuple):
    recall: Float
    precision: Float
    corner_error: Float
    found: Int
    missed: Int
    false_positives: Int


@node("matching.score_instances", version=1)
def score_instances(
    instances: Instances,
    scenes: ObjectScenes,
    *,
    iou: Annotated[float, Field(gt=0, le=1)] = 0.5,
) -> InstanceScores:
    r"""Found instances against the true quadrilaterals: recall, precision, corner error.

    A found instance is a true positive when its quadrilateral overlaps a true one of its
    scene by a polygon IoU :math:`|A \cap B| / |A \cup B| \ge` ``iou`` (each true instance
    found once, best supported first; :func:`match_instances`). Then

    .. math:: \text{recall} = \frac{TP}{TP + FN}, \qquad
              \text{precision} = \frac{TP}{TP + FP}, \qquad
              e = \operatorname{median}_{TP} \frac14 \sum_{c=1}^{4} \|\hat q_c - q_c\|

    where :math:`\hat q_c` and :math:`q_c` are the found and the true images of model
    corner :math:`c` (so a pose turned by 90° is found by IoU but has a large corner
    error). Recall is 1 when there is nothing to find, precision 1 when nothing is
    found, the corner error infinite when no instance is found.

    Parameters
    ----------
    instances : Instances
        What a detector found (``matching.find_instances_in_scenes``).
    scenes : ObjectScenes
        The scenes with their true instances.
    iou : float
        Least polygon IoU of a true positive (PASCAL VOC's 0.5).

    Returns
    -------
    recall, precision : float
    corner_error : float
        Median over true positives of the mean distance of the four corners, pixels.
    found, missed, false_positives : int
        True positives, false negatives, false positives.

    References
    ----------
    .. [1] M. Everingham et al., "The PASCAL visual object classes (VOC) challenge",
       IJCV 88(2), 2010 (overlap criterion).
    .. [2] D. DeTone, T. Malisiewicz, A. Rabinovich, "Deep image homography
       estimation", 2016 (mean corner error of a homography).
    """
    hits = match_instances(instances, scenes, iou)
    true_positive = hits >= 0
    tp = int(true_positive.sum())
    errors = [
        float(np.linalg.norm(instances.quads[i] - scenes.quads[hits[i]], axis=1).mean())
        for i in np.flatnonzero(true_positive)
    ]
    total = len(scenes.owner)
    return InstanceScores(
        tp / total if total else 1.0,
        tp / len(instances) if len(instances) else 1.0,
        float(np.median(errors)) if errors else math.inf,
        tp,
        total - tp,
        len(instances) - tp,
    )
