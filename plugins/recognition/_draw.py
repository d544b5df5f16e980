"""Pictures of a classifier's results: which samples it got right and which wrong, and the
table a report turns into a confusion matrix."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import Array, ColorImage, Table, node

from ._types import Features, Samples

__all__ = ["draw_predictions", "prediction_mosaic", "predictions"]

_RIGHT = np.array([0.18, 0.62, 0.20], np.float32)  # green frame
_WRONG = np.array([0.80, 0.11, 0.11], np.float32)  # red frame
_SIDE = 32  # a sample is enlarged (nearest neighbour) until its shorter side is this


def _checked(labels: np.ndarray, predicted: np.ndarray) -> None:
    if predicted.shape != labels.shape:
        raise ValueError(
            f"predicted labels have shape {predicted.shape}, the samples have "
            f"{len(labels)} labels: give the predictions of these samples"
        )


@node("recognition.predictions", version=1)
def predictions(features: Features, predicted: Array) -> Table:
    """Each sample's true label beside the one predicted: a report shows this table as a
    confusion matrix (rows the true class, columns the predicted one).

    Parameters
    ----------
    features : Features carrying the true labels
    predicted : (N,) labels, one per sample (``recognition.predict``)

    Returns
    -------
    Table
        Columns ``label`` (true) and ``predicted``, int64.

    References
    ----------
    .. [1] R. Kohavi, F. Provost, "Glossary of terms", *Machine Learning* 30, 1998
       (the confusion matrix).
    """
    _checked(features.labels, predicted)
    return {"label": features.labels.astype(np.int64), "predicted": predicted.astype(np.int64)}


def prediction_mosaic(
    images: np.ndarray, labels: np.ndarray, predicted: np.ndarray, count: int
) -> np.ndarray:
    """Up to ``count`` right predictions (top row, green frames) and ``count`` wrong ones
    (bottom row, red frames), the first of each in sample order; each sample stretched to
    [0, 1] and enlarged to at least 32 pixels."""
    _checked(labels, predicted)
    height, width = images.shape[1:3]
    factor = max(1, int(np.ceil(_SIDE / min(height, width))))
    cell_h, cell_w = height * factor + 4, width * factor + 4
    rows = [
        np.flatnonzero(predicted == labels)[:count],
        np.flatnonzero(predicted != labels)[:count],
    ]
    canvas = np.ones((2 * cell_h + 2, count * (cell_w + 2), 3), np.float32)
    for r, (chosen, frame) in enumerate(zip(rows, (_RIGHT, _WRONG), strict=True)):
        for c, index in enumerate(chosen):
            image = images[index].astype(np.float32)
            low, span = float(image.min()), float(image.max() - image.min())
            image = (image - low) / span if span > 0 else np.zeros_like(image)
            big = np.repeat(np.repeat(image, factor, axis=0), factor, axis=1)
            top, left = r * (cell_h + 2), c * (cell_w + 2)
            canvas[top : top + cell_h, left : left + cell_w] = frame
            canvas[top + 2 : top + cell_h - 2, left + 2 : left + cell_w - 2] = big[..., None]
    return canvas


@node("recognition.draw_predictions", version=1)
def draw_predictions(
    samples: Samples, predicted: Array, *, count: Annotated[int, Field(ge=1, le=64)] = 8
) -> ColorImage:
    """A sample of a classifier's right and wrong predictions, as a picture.

    The top row holds the first ``count`` samples whose predicted label equals
    their true one, framed green; the bottom row the first ``count`` it got
    wrong, framed red (an empty place when there are fewer).

    Parameters
    ----------
    samples : Samples
        The classified samples, with their true labels.
    predicted : Array
        The predicted label of each sample (``recognition.predict``).
    count : int
        Samples shown per row.
    """
    return prediction_mosaic(samples.images, samples.labels, np.asarray(predicted), count)
