"""Training a network by mini-batch SGD with momentum, and applying it (seed: "We use
gradient descent for adjusting the weights")."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Annotated

import numpy as np
from pydantic import Field

from graphvision import Float, Table, node, one_blas_thread

from ..recognition._types import Samples, SampleSet
from ..shared.params import Count, Epochs, Positive, Seed
from ._layers import softmax_cross_entropy
from ._network import (
    MAX_BATCH_VALUES,
    Architecture,
    Network,
    NetworkModel,
    build_architecture,
    initial_weights,
)

__all__ = [
    "Curves",
    "accuracy",
    "check_layer_texts",
    "fit_network",
    "fit_network_curves",
    "predict",
    "train",
]

DEFAULT_LAYERS = ["conv 16x3", "relu", "maxpool 2", "conv 32x3", "relu", "maxpool 2", "dense 10"]
DIVERGENCE_FACTOR = 20.0
"""The loss is taken as diverged when it is not finite or exceeds this many times the
loss of guessing (log K for K classes)."""
STUCK_FRACTION = 0.98
"""Training that ends (after two epochs or more) with a loss above this fraction of the
entropy of the class frequencies (the loss of guessing them) learned nothing: a learning
rate too high for the ReLUs (they die: every output zero) leaves the loss there without
diverging."""


@dataclass(frozen=True)
class Curves:
    """What training recorded, one value per epoch: the mean loss, the training accuracy
    (of the batches as they were trained on, read from the scores the loss was computed
    from: no further pass) and the held-out accuracy after the epoch (empty when no
    held-out samples were given)."""

    loss: np.ndarray
    accuracy: np.ndarray
    held_out: np.ndarray


def fit_network(
    architecture: Architecture,
    images: np.ndarray,
    targets: np.ndarray,
    *,
    epochs: int,
    batch_size: int,
    learning_rate: float,
    momentum: float,
    weight_decay: float,
    seed: int,
    what: str = "cnn.train",
) -> tuple[np.ndarray, np.ndarray]:
    """The weights and the mean loss of each epoch of :func:`fit_network_curves` (no
    held-out samples)."""
    weights, curves = fit_network_curves(
        architecture, images, targets, epochs=epochs, batch_size=batch_size,
        learning_rate=learning_rate, momentum=momentum, weight_decay=weight_decay,
        seed=seed, what=what,
    )  # fmt: skip
    return weights, curves.loss


def fit_network_curves(
    architecture: Architecture,
    images: np.ndarray,
    targets: np.ndarray,
    *,
    epochs: int,
    batch_size: int,
    learning_rate: float,
    momentum: float,
    weight_decay: float,
    seed: int,
    what: str = "cnn.train",
    held_out: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, Curves]:
    r"""Minimise the mean softmax cross-entropy over ``images`` (N, C, H, W) with class
    indices ``targets`` by mini-batch SGD with momentum:

    .. math::
        v \leftarrow \mu v - \eta (\nabla_w L + \lambda w),\qquad w \leftarrow w + v

    over batches of a seeded permutation, each epoch, in float32. Returns the weights and
    the :class:`Curves` of each epoch: the mean loss, the training accuracy
    :math:`\frac{1}{N}\sum_i [\arg\max_k s_{ik} = y_i]` over the batches' scores, and
    the accuracy on ``held_out`` (images, class indices; -1 for a class the training set
    lacks, always wrong) after the epoch. Raises ValueError naming ``what`` and the
    learning rate when the loss diverges (not finite, or above ``DIVERGENCE_FACTOR`` ·
    log K), so no NaN weight ever leaves, or when it ends where guessing the class
    frequencies would (``STUCK_FRACTION``), and, before training, when a batch would make
    more than ``MAX_BATCH_VALUES`` values in the largest layer.

    References
    ----------
    B. T. Polyak, "Some methods of speeding up the convergence of iteration methods", 1964;
    Y. LeCun et al., "Efficient BackProp", 1998.
    """
    batch = min(batch_size, len(images))
    if batch * architecture.sample_values > MAX_BATCH_VALUES:
        most = max(MAX_BATCH_VALUES // architecture.sample_values, 1)
        raise ValueError(
            f"{what}: a batch of {batch} inputs would make {batch * architecture.sample_values:,} "
            f"values in the network's largest layer, at most {MAX_BATCH_VALUES:,}: set "
            f"batch_size to {most} or less"
        )
    settings = _Settings(batch_size, learning_rate, momentum, weight_decay, what)
    with one_blas_thread():
        weights, curves = _sgd(architecture, images, targets, epochs, seed, settings, held_out)
    _check_learned(curves.loss, targets, epochs, learning_rate, what)
    return weights, curves


@dataclass(frozen=True)
class _Settings:
    batch_size: int
    learning_rate: float
    momentum: float
    weight_decay: float
    what: str


def _sgd(
    architecture: Architecture,
    images: np.ndarray,
    targets: np.ndarray,
    epochs: int,
    seed: int,
    settings: _Settings,
    held_out: tuple[np.ndarray, np.ndarray] | None,
) -> tuple[np.ndarray, Curves]:
    rng = np.random.default_rng(seed)
    images = np.asarray(images, np.float32)  # float32 halves BLAS's work; weights return float64
    weights = initial_weights(architecture, seed).astype(np.float32)
    velocity = np.zeros_like(weights)
    classes = architecture.shapes[-1][0]
    ceiling = DIVERGENCE_FACTOR * max(np.log(classes), 1.0)
    loss, accuracy, kept = [], [], []
    for epoch in range(epochs):
        order = rng.permutation(len(images))
        total, right = 0.0, 0
        for start in range(0, len(order), settings.batch_size):
            batch = order[start : start + settings.batch_size]
            scores, saved = architecture.forward(weights, images[batch], keep=True)
            value, grad = softmax_cross_entropy(scores, targets[batch])
            if not np.isfinite(value) or value > ceiling:
                raise ValueError(
                    f"{settings.what}: the loss diverged (loss {value:.3g} at epoch {epoch + 1}, "
                    f"batch {start // settings.batch_size + 1}) with "
                    f"learning_rate={settings.learning_rate:g}; lower the learning rate"
                )
            gradient = architecture.backward(weights, grad.astype(np.float32), saved)
            gradient += settings.weight_decay * weights
            velocity *= settings.momentum
            velocity -= settings.learning_rate * gradient
            weights = weights + velocity
            total += value * len(batch)
            right += int(np.count_nonzero(scores.argmax(axis=1) == targets[batch]))
        loss.append(total / len(order))
        accuracy.append(right / len(order))
        if held_out is not None:
            kept.append(_accuracy(architecture, weights, *held_out, settings.batch_size))
    if not np.isfinite(weights).all():
        raise ValueError(
            f"{settings.what}: the weights are not finite with "
            f"learning_rate={settings.learning_rate:g}"
        )
    curves = Curves(np.array(loss), np.array(accuracy), np.array(kept, np.float64))
    return weights.astype(np.float64), curves


def _accuracy(
    architecture: Architecture, weights: np.ndarray, images: np.ndarray, targets: np.ndarray,
    batch: int,
) -> float:  # fmt: skip
    """The fraction of ``images`` whose highest score is their target, batch by batch."""
    right = 0
    for start in range(0, len(images), batch):
        scores, _ = architecture.forward(weights, images[start : start + batch])
        right += int(np.count_nonzero(scores.argmax(axis=1) == targets[start : start + batch]))
    return right / max(len(images), 1)


def _check_learned(
    loss: np.ndarray, targets: np.ndarray, epochs: int, learning_rate: float, what: str
) -> None:
    """ValueError when the last epoch's loss is that of guessing the class frequencies."""
    frequency = np.bincount(targets) / len(targets)
    frequency = frequency[frequency > 0]
    guessing = float(-(frequency * np.log(frequency)).sum())
    if epochs >= 2 and guessing > 0 and loss[-1] >= STUCK_FRACTION * guessing:
        raise ValueError(
            f"{what}: the network learned nothing: after {epochs} epochs the loss "
            f"{loss[-1]:.3g} is that of guessing the class frequencies ({guessing:.3g}) "
            f"with learning_rate={learning_rate:g}; its ReLUs may have died: lower the "
            "learning rate"
        )


def check_layer_texts(texts: list[str], name: str = "layers") -> None:
    """ValueError naming the parameter ``name`` and the layer's index when a text is not a
    layer or exceeds a layer's maxima (their chaining needs the input shape, so the node
    checks it)."""
    from ._layers import parse_layer

    for number, text in enumerate(texts):
        try:
            parse_layer(text)
        except ValueError as error:
            raise ValueError(f"{name}[{number}]: {error}") from None


def _layers_parse(layers: list[str], **_: object) -> None:
    """The layer list is not empty and each text is a layer."""
    if not layers:
        raise ValueError("layers is empty; give at least one layer, e.g. ['dense 10']")
    check_layer_texts(layers)


@node("cnn.train", version=2, check=_layers_parse)
def train(
    train: Samples,
    held_out: Samples | None = None,
    *,
    layers: list[str] = DEFAULT_LAYERS,
    epochs: Epochs = 15,
    batch_size: Count = 32,
    learning_rate: Positive = 0.05,
    momentum: Annotated[float, Field(ge=0, lt=1)] = 0.9,
    weight_decay: Annotated[float, Field(ge=0)] = 1e-4,
    seed: Seed = 0,
) -> Network:
    r"""Build a network from its layer list and train it on labelled images by mini-batch
    SGD with momentum, the loss being the softmax cross-entropy of the last layer.

    A layer list of one ``dense K`` layer is softmax regression (a linear classifier).
    The layers are chained from the images' shape (1, H, W) before any training: a
    layer whose input does not fit is refused, naming it. Training stops with an error
    naming the learning rate when the loss diverges.

    Parameters
    ----------
    train : Samples
        Images (N, H, W) in [0, 1] and their labels.
    held_out : Samples, optional
        Images of the same shape kept out of training: their accuracy is measured after
        each epoch (never trained on), the held-out curve.
    layers : list of str
        ``conv FxK`` (F filters K×K, padded by K // 2; ``pad P`` to choose), ``relu``,
        ``maxpool S``, ``dense U``; the last must be ``dense`` with one unit per class.
        At most 4,096 filters or units, K ≤ 31, P < 31, S ≤ 32, and at most 10 million
        weights for the images' shape (``parse_layer``, ``build_architecture``).
    epochs : int
        Passes over the training set (at most 1,000).
    batch_size : int
        Images per gradient step.
    learning_rate : float
        Step size η.
    momentum : float
        Momentum μ.
    weight_decay : float
        L2 penalty λ on every weight.
    seed : int
        Seed of the initial weights and of the batch order.

    Returns
    -------
    Network
        The trained network with its curves, one value per epoch: the mean loss
        (``history``), the training accuracy :math:`\frac{1}{N}\sum_i [\hat y_i = y_i]`
        of the batches as they were trained on (``accuracy``) and the accuracy on
        ``held_out`` after the epoch (``held_out_accuracy``, empty without it).

    References
    ----------
    Y. LeCun et al., "Gradient-based learning applied to document recognition", Proc.
    IEEE 86(11), 1998.
    """
    classes, targets = np.unique(train.labels, return_inverse=True)
    architecture = build_architecture((1, *train.images.shape[1:]), list(layers))
    if architecture.shapes[-1] != (len(classes),):
        raise ValueError(
            f"layer {len(layers) - 1} '{layers[-1]}' gives {architecture.shapes[-1]} outputs "
            f"but the samples have {len(classes)} classes; end with 'dense {len(classes)}'"
        )
    images = train.images[:, None]
    weights, curves = fit_network_curves(
        architecture,
        images,
        targets,
        epochs=epochs,
        batch_size=batch_size,
        learning_rate=learning_rate,
        momentum=momentum,
        weight_decay=weight_decay,
        seed=seed,
        held_out=_held_out(held_out, classes, train.images.shape[1:]),
    )
    spec = json.dumps({"input": list(architecture.shapes[0]), "layers": list(layers)})
    return NetworkModel(
        spec, weights, classes.astype(np.int64), curves.loss, curves.accuracy, curves.held_out
    )


def _held_out(
    samples: SampleSet | None, classes: np.ndarray, shape: tuple[int, ...]
) -> tuple[np.ndarray, np.ndarray] | None:
    """Held-out images (N, 1, H, W) float32 and their class indices (-1 for a label the
    training samples lack: never predicted, so always wrong); ValueError when their
    images are not the training images' shape."""
    if samples is None:
        return None
    if samples.images.shape[1:] != shape:
        raise ValueError(
            f"held_out images are {samples.images.shape[1:]} (H, W) but the training images "
            f"are {shape}: give held-out samples of the same size"
        )
    index = np.searchsorted(classes, samples.labels).clip(0, len(classes) - 1)
    targets = np.where(classes[index] == samples.labels, index, -1)
    return samples.images[:, None].astype(np.float32), targets


def predicted_labels(network: NetworkModel, samples: SampleSet) -> tuple[np.ndarray, np.ndarray]:
    scores = network.scores(samples.images)
    shifted = np.exp(scores - scores.max(axis=1, keepdims=True))
    probability = shifted / shifted.sum(axis=1, keepdims=True)
    best = probability.argmax(axis=1)
    return network.classes[best], probability[np.arange(len(best)), best]


@node("cnn.predict", version=1)
def predict(network: Network, samples: Samples) -> Table:
    """The class of each sample by the network, with its softmax probability.

    Parameters
    ----------
    network : Network
        A trained network.
    samples : Samples
        Images of the shape the network was trained on.

    Returns
    -------
    Table
        Columns ``label`` (the samples' own), ``predicted``, ``probability``.
    """
    predicted, probability = predicted_labels(network, samples)
    return {"label": samples.labels, "predicted": predicted, "probability": probability}


@node("cnn.accuracy", version=1)
def accuracy(network: Network, samples: Samples) -> Float:
    """The fraction of samples the network classifies correctly.

    Parameters
    ----------
    network : Network
        A trained network.
    samples : Samples
        Held-out images with their labels.

    Returns
    -------
    float
        Accuracy in [0, 1].
    """
    predicted, _ = predicted_labels(network, samples)
    return float(np.mean(predicted == samples.labels))
