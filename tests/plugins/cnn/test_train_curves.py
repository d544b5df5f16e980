"""cnn.train records, per epoch, the training accuracy and the accuracy on held-out
samples beside the loss (the curves the studio and report.html draw)."""

from __future__ import annotations

import numpy as np
import pytest

import graphvision as gv
from graphvision_plugins import cnn
from graphvision_plugins.recognition._types import SampleSet


def _halves(count: int, seed: int, side: int = 6) -> SampleSet:
    """Images bright on the left half (label 3) or the right half (label 5), with noise:
    the class is the brighter half."""
    rng = np.random.default_rng(seed)
    labels = np.where(np.arange(count) % 2 == 0, 3, 5).astype(np.int64)
    images = rng.uniform(0.0, 0.4, (count, side, side)).astype(np.float32)
    for image, label in zip(images, labels, strict=True):
        half = slice(0, side // 2) if label == 3 else slice(side // 2, side)
        image[:, half] += 0.5
    return SampleSet(images.clip(0, 1), labels)


def test_the_held_out_curve_ends_at_the_trained_networks_accuracy():
    train, held_out = _halves(40, seed=1), _halves(30, seed=2)
    network = cnn.train(train, held_out, layers=["dense 2"], epochs=4, learning_rate=0.1)
    assert network.history.shape == network.accuracy.shape == (4,)
    assert network.held_out_accuracy.shape == (4,)
    assert cnn.NetworkPort.validate(network) is network
    # the accuracy node measures the final weights on its own: the curve's last point
    assert network.held_out_accuracy[-1] == cnn.accuracy(network, held_out)
    assert network.held_out_accuracy[-1] > 0.9  # the brighter half separates the classes


def test_the_training_accuracy_is_that_of_the_weights_each_batch_was_scored_with():
    # one batch per epoch: epoch k's batch is scored with the weights epoch k - 1 ended
    # with, which the held-out curve (here the training set itself) measured
    train = _halves(24, seed=3)
    network = cnn.train(train, train, layers=["dense 2"], epochs=5, batch_size=24,
                        learning_rate=0.2, momentum=0.0)  # fmt: skip
    np.testing.assert_array_equal(network.accuracy[1:], network.held_out_accuracy[:-1])
    assert network.accuracy.min() >= 0 and network.accuracy.max() <= 1


def test_without_held_out_samples_the_held_out_curve_is_empty():
    network = cnn.train(_halves(20, seed=4), layers=["dense 2"], epochs=2, learning_rate=0.1)
    assert network.accuracy.shape == (2,) and network.held_out_accuracy.shape == (0,)


def test_a_held_out_class_the_training_set_lacks_counts_as_wrong():
    train = _halves(40, seed=5)
    stranger = SampleSet(train.images[:10], np.full(10, 9, np.int64))  # label 9: never trained
    both = SampleSet(np.concatenate([train.images[:10], stranger.images]),
                     np.concatenate([train.labels[:10], stranger.labels]))  # fmt: skip
    network = cnn.train(train, both, layers=["dense 2"], epochs=3, learning_rate=0.1)
    assert network.held_out_accuracy[-1] == cnn.accuracy(network, both)
    assert network.held_out_accuracy.max() <= 0.5  # half of them can never be right


def test_held_out_images_of_another_size_are_refused_naming_both_sizes():
    expected = r"held_out images are \(4, 4\).*training images are \(6, 6\)"
    with pytest.raises(ValueError, match=expected):
        cnn.train(_halves(10, seed=6), _halves(4, seed=7, side=4), layers=["dense 2"], epochs=1)


def test_a_network_whose_curve_is_not_a_vector_is_refused():
    network = cnn.train(_halves(10, seed=8), layers=["dense 2"], epochs=1)
    broken = cnn.NetworkModel(network.architecture, network.weights, network.classes,
                              network.history, np.zeros((1, 1)))  # fmt: skip
    with pytest.raises(gv.PortValueError, match="Network 'accuracy' must be a vector"):
        cnn.NetworkPort.validate(broken)
