"""A classifier's pictures: the results table behind the confusion matrix, and a sample of
right (green) and wrong (red) predictions."""

from __future__ import annotations

import numpy as np
import pytest

from graphvision_plugins import recognition as rec
from graphvision_plugins.recognition._types import FeatureSet, SampleSet

GREEN = np.array([0.18, 0.62, 0.20], np.float32)
RED = np.array([0.80, 0.11, 0.11], np.float32)


def _samples() -> SampleSet:
    images = np.zeros((5, 8, 8), np.float32)
    for index in range(5):
        images[index, index, :] = 1.0  # sample i: a white row i
    return SampleSet(images, np.array([0, 0, 1, 1, 1], np.int64))


def test_the_results_table_pairs_each_true_label_with_the_predicted_one():
    labels = np.array([0, 0, 1, 1, 1], np.int64)
    given = FeatureSet(np.zeros((5, 2)), labels, "{}")
    table = rec.predictions(given, np.array([0, 1, 1, 1, 0], np.int64))
    assert table["label"].tolist() == [0, 0, 1, 1, 1]
    assert table["predicted"].tolist() == [0, 1, 1, 1, 0]


def test_right_predictions_are_framed_green_on_top_and_wrong_ones_red_below():
    predicted = np.array([0, 1, 1, 1, 0], np.int64)  # samples 1 and 4 wrong
    picture = rec.draw_predictions(_samples(), predicted, count=3)
    cell = 8 * 4 + 4  # 8-pixel samples enlarged 4× to 32, in a 2-pixel frame
    assert picture.shape == (2 * cell + 2, 3 * (cell + 2), 3)
    for column in range(3):  # right: samples 0, 2, 3
        assert np.allclose(picture[0, column * (cell + 2)], GREEN)
    for column, sample in enumerate([1, 4]):
        left, top = column * (cell + 2), cell + 2
        assert np.allclose(picture[top, left], RED)
        inside = picture[top + 2 : top + cell - 2, left + 2 : left + cell - 2, 0]
        assert inside[sample * 4 : sample * 4 + 4].min() == 1.0  # its white row, enlarged
        assert inside.sum() == 4 * 32  # and nothing else
    assert np.all(picture[cell + 2 :, 2 * (cell + 2) :] == 1.0)  # two wrong only: blank


def test_predictions_of_other_samples_are_refused():
    with pytest.raises(ValueError, match=r"predicted labels have shape \(3,\), the samples have 5"):
        rec.draw_predictions(_samples(), np.zeros(3, np.int64))
    given = FeatureSet(np.zeros((5, 2)), np.zeros(5, np.int64), "{}")
    with pytest.raises(ValueError, match="give the predictions of these samples"):
        rec.predictions(given, np.zeros(4, np.int64))
