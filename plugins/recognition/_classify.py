"""Applying any trained classifier, and measuring it."""

from __future__ import annotations

import numpy as np

from graphvision import Array, Float, node

from ._models import Classifier
from ._types import Features

__all__ = ["accuracy", "predict"]


@node("recognition.predict", version=1)
def predict(classifier: Classifier, features: Features) -> Array:
    """The label the classifier gives each row of ``features``.

    Parameters
    ----------
    classifier : any Classifier (linear SVM, boosted stumps, 1-NN, cascade)
    features : Features computed as the classifier's training features were

    Returns
    -------
    labels : (N,) int64
    """
    return np.asarray(classifier.predict(features.features), np.int64)


@node("recognition.accuracy", version=1)
def accuracy(features: Features, predicted: Array) -> Float:
    """The fraction of samples whose predicted label equals their true label.

    Parameters
    ----------
    features : Features carrying the true labels
    predicted : (N,) labels, one per sample

    Returns
    -------
    accuracy : float in [0, 1]
    """
    if predicted.shape != features.labels.shape:
        raise ValueError(
            f"predicted labels have shape {predicted.shape}, the features have "
            f"{len(features.labels)} samples"
        )
    return float(np.mean(predicted == features.labels))
