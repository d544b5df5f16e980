"""scikit-learn's 8×8 digits as labelled samples (scikit-learn is an optional extra)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from graphvision import node

from ..recognition._data import stratified_split
from ..recognition._types import Samples, SampleSet
from ..shared.params import Probability, Seed

__all__ = ["digits", "load_digits_images"]


class DigitSplit(NamedTuple):
    train: Samples
    test: Samples


def load_digits_images() -> tuple[np.ndarray, np.ndarray]:
    """The 1,797 digits of scikit-learn as float32 images (N, 8, 8) in [0, 1] (the 0..16
    gray levels divided by 16) and their int64 labels; ImportError naming the extra when
    scikit-learn is missing."""
    try:
        from sklearn.datasets import load_digits
    except ImportError:
        raise ImportError(
            "the 8×8 digits ship with scikit-learn, which is not installed: "
            "pip install scikit-learn (or the 'dev' or 'bench' extra of graphvision)"
        ) from None
    data = load_digits()
    return (data.images / 16.0).astype(np.float32), data.target.astype(np.int64)


@node("cnn.digits", version=1)
def digits(
    *,
    test_fraction: Probability = 0.2,
    seed: Seed = 0,
) -> DigitSplit:
    """scikit-learn's 8×8 handwritten digits (1,797 images, classes 0–9), split per class
    at random (seeded) into training and test sets.

    Parameters
    ----------
    test_fraction : float
        Fraction of each class held out for testing (0.2: the issue's 80/20 split).
        A fraction leaving a class no training sample, or no test sample at all, is
        refused.
    seed : int
        Seed of the split.

    Returns
    -------
    train, test : Samples (N, 8, 8)

    References
    ----------
    E. Alpaydin and C. Kaynak, "Optical recognition of handwritten digits", UCI machine
    learning repository, 1998.
    """
    images, labels = load_digits_images()
    train, test = stratified_split(labels, test_fraction, seed)
    return DigitSplit(
        SampleSet(images[train], labels[train]), SampleSet(images[test], labels[test])
    )
