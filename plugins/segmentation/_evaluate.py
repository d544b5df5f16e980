"""Scoring a labelling against the true labels: the confusion matrix, the intersection over
union of each class and its mean, and the pixel accuracy (Long et al. 2015, section 5)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from graphvision import Float, Table, node

from ..synthetic._shape_scenes import LabelledScenes

__all__ = ["SegmentationScores", "class_iou", "confusion_matrix", "evaluate"]


def confusion_matrix(truth: np.ndarray, predicted: np.ndarray, classes: int) -> np.ndarray:
    """``n[i, j]``: the number of pixels of true class i labelled j (int64, K × K)."""
    if truth.shape != predicted.shape:
        raise ValueError(
            f"the true labels {truth.shape} and the predicted ones {predicted.shape} must "
            "have the same shape"
        )
    pairs = truth.ravel().astype(np.int64) * classes + predicted.ravel()
    return np.bincount(pairs, minlength=classes * classes).reshape(classes, classes)


def class_iou(confusion: np.ndarray) -> np.ndarray:
    r"""The intersection over union of each class,
    :math:`n_{ii} / (t_i + \sum_j n_{ji} - n_{ii})` with :math:`t_i = \sum_j n_{ij}`; NaN for
    a class neither true nor predicted anywhere."""
    hits = np.diag(confusion).astype(np.float64)
    union = confusion.sum(axis=1) + confusion.sum(axis=0) - hits
    iou = np.full(len(hits), np.nan)
    np.divide(hits, union, out=iou, where=union > 0)
    return iou


class SegmentationScores(NamedTuple):
    miou: Float
    pixel_accuracy: Float
    classes: Table


@node("segmentation.evaluate", version=1)
def evaluate(predicted: LabelledScenes, truth: LabelledScenes) -> SegmentationScores:
    r"""The mean intersection over union and the pixel accuracy of a labelling, from the
    confusion matrix :math:`n_{ij}` (pixels of class i labelled j) summed over every
    scene, :math:`t_i = \sum_j n_{ij}`:

    .. math::
        \text{pixel accuracy} = \frac{\sum_i n_{ii}}{\sum_i t_i},\qquad
        \text{mean IU} = \frac{1}{n_{cl}} \sum_i \frac{n_{ii}}{t_i + \sum_j n_{ji} - n_{ii}}

    The mean runs over the classes (the background included, as PASCAL VOC counts it)
    that are true or predicted somewhere.

    Parameters
    ----------
    predicted : LabelledScenes
        The labelling (e.g. ``segmentation.predict``'s).
    truth : LabelledScenes
        The same scenes with their true labels and the same class names.

    Returns
    -------
    miou : float
        Mean intersection over union in [0, 1].
    pixel_accuracy : float
        Fraction of pixels labelled right.
    classes : Table
        Per class: ``name``, ``iou``, ``pixels`` (true) and ``predicted`` (pixel counts).

    References
    ----------
    J. Long, E. Shelhamer, T. Darrell, "Fully convolutional networks for semantic
    segmentation", CVPR 2015, section 5 (pixel accuracy, mean IU).
    """
    names = truth.class_names
    if predicted.class_names != names:
        raise ValueError(
            f"the labelling names the classes {predicted.class_names} but the truth "
            f"{names}: compare labellings of the same classes"
        )
    confusion = confusion_matrix(truth.labels, predicted.labels, len(names))
    iou = class_iou(confusion)
    table = {
        "name": np.array(names),
        "iou": iou,
        "pixels": confusion.sum(axis=1),
        "predicted": confusion.sum(axis=0),
    }
    accuracy = float(np.trace(confusion) / max(confusion.sum(), 1))
    return SegmentationScores(float(np.nanmean(iou)), accuracy, table)
