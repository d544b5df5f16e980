"""Training an encoder–decoder network per pixel (Adam on the pixel cross-entropy), and
labelling scenes with it."""

from __future__ import annotations

import json
from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from graphvision import node, one_blas_thread

from ..shared.params import Count, Epochs, Positive, Seed
from ..synthetic._shape_scenes import LabelledScenes, LabelledSceneSet
from ._model import MAX_LEVELS, MAX_WIDTH, Segmenter, SegmenterModel
from ._unet import UNet, build_unet, pixel_cross_entropy

__all__ = ["class_weights", "fit_unet", "predict", "train"]

BETAS = (0.9, 0.999)
"""Adam's decay rates of the first and second moments (Kingma and Ba's defaults)."""
EPSILON = 1e-8
"""Adam's denominator offset."""
MAX_BATCH_PIXELS = 2**18
"""Most pixels of a training batch: the largest activation of an [8, 16, 32] U-Net at
2^18 pixels (im2col of the last level: 2^18 × 144 float32) is 150 MB."""

Width = Annotated[int, Field(ge=1, le=MAX_WIDTH)]


def class_weights(labels: np.ndarray, classes: int, weighting: str) -> np.ndarray:
    r"""Per-class weights of the loss: ones (``none``), or median frequency balancing
    (``median_frequency``), :math:`w_k = \mathrm{median}_j f_j / f_k` with :math:`f_k`
    the fraction of class k among the training pixels (a class absent from them gets 1).

    References
    ----------
    D. Eigen, R. Fergus, "Predicting depth, surface normals and semantic labels with a
    common multi-scale convolutional architecture", ICCV 2015, section 4.3.
    """
    if weighting == "none":
        return np.ones(classes, np.float32)
    frequency = np.bincount(labels.ravel(), minlength=classes)[:classes] / labels.size
    present = frequency > 0
    weights = np.ones(classes)
    weights[present] = np.median(frequency[present]) / frequency[present]
    return weights.astype(np.float32)


def _augment(
    images: np.ndarray, labels: np.ndarray, crop: int, rng: np.random.Generator, turn: bool
) -> tuple:
    """The batch cut to a random ``crop`` × ``crop`` window (0: whole), turned by a random
    multiple of 90° and mirrored at random (the same for images and labels: the classes
    are shapes, invariant under both)."""
    if crop:
        top, left = (
            rng.integers(0, images.shape[1] - crop + 1),
            rng.integers(0, images.shape[2] - crop + 1),
        )
        images = images[:, top : top + crop, left : left + crop]
        labels = labels[:, top : top + crop, left : left + crop]
    if not turn:
        return np.ascontiguousarray(images), np.ascontiguousarray(labels)
    turns, mirror = int(rng.integers(4)), bool(rng.integers(2))
    images, labels = np.rot90(images, turns, axes=(1, 2)), np.rot90(labels, turns, axes=(1, 2))
    if mirror:
        images, labels = images[:, :, ::-1], labels[:, :, ::-1]
    return np.ascontiguousarray(images), np.ascontiguousarray(labels)


def fit_unet(
    net: UNet,
    images: np.ndarray,
    labels: np.ndarray,
    *,
    weights_per_class: np.ndarray,
    epochs: int,
    batch_size: int,
    learning_rate: float,
    augment: bool,
    seed: int,
    crop: int = 0,
    cosine: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Minimise the pixel cross-entropy over ``images`` (N, H, W) with ``labels`` by Adam
    on mini-batches of a seeded permutation (each scene cut to a random ``crop`` × ``crop``
    window when ``crop`` is not 0), in float32:

    .. math::
        m \leftarrow \beta_1 m + (1 - \beta_1) g,\quad
        v \leftarrow \beta_2 v + (1 - \beta_2) g^2,\quad
        w \leftarrow w - \eta_t\,\frac{m / (1 - \beta_1^t)}{\sqrt{v / (1 - \beta_2^t)} + \epsilon}

    with the step size annealed on a cosine, :math:`\eta_t = \eta\,\tfrac12(1 + \cos(\pi
    (t - 1) / T))` over the T steps (constant when ``cosine`` is off).

    Returns the weights (float64), the mean loss and the training pixel accuracy of each
    epoch; ValueError naming the learning rate when the loss is not finite.

    References
    ----------
    D. P. Kingma, J. Ba, "Adam: a method for stochastic optimization", ICLR 2015;
    I. Loshchilov, F. Hutter, "SGDR: stochastic gradient descent with warm restarts",
    ICLR 2017 (the cosine schedule).
    """
    rng = np.random.default_rng(seed)
    weights = net.initial_weights(seed).astype(np.float32)
    first, second = np.zeros_like(weights), np.zeros_like(weights)
    x_all = np.asarray(images, np.float32)
    history, accuracy, t = [], [], 0
    steps = epochs * -(-len(x_all) // batch_size)
    with one_blas_thread():
        for epoch in range(epochs):
            order = rng.permutation(len(x_all))
            losses, correct = 0.0, 0
            for start in range(0, len(order), batch_size):
                batch = order[start : start + batch_size]
                x, y = x_all[batch], labels[batch]
                if augment or crop:
                    x, y = _augment(x, y, crop, rng, turn=augment)
                scores, saved = net.forward(weights, x[..., None], keep=True)
                loss, grad = pixel_cross_entropy(scores, y, weights_per_class)
                if not np.isfinite(loss):
                    raise ValueError(
                        f"segmentation.train: the loss is not finite at epoch {epoch + 1} "
                        f"with learning_rate={learning_rate:g}; lower the learning rate"
                    )
                g = net.backward(weights, grad.astype(np.float32), saved)
                t += 1
                first *= BETAS[0]
                first += (1 - BETAS[0]) * g
                second *= BETAS[1]
                second += (1 - BETAS[1]) * g * g
                rate = learning_rate * (
                    0.5 + 0.5 * np.cos(np.pi * (t - 1) / steps) if cosine else 1
                )
                step = first / (1 - BETAS[0] ** t)
                weights -= rate * step / (np.sqrt(second / (1 - BETAS[1] ** t)) + EPSILON)
                losses += loss * len(batch)
                correct += int((scores.argmax(axis=3) == y).sum())
            history.append(losses / len(order))
            accuracy.append(correct / (len(order) * x.shape[1] * x.shape[2]))
    return weights.astype(np.float64), np.array(history), np.array(accuracy)


def _check_train(widths: list[int], batch_size: int, **_: object) -> None:
    """At least two levels, at most ``MAX_LEVELS``."""
    if not 2 <= len(widths) <= MAX_LEVELS:
        raise ValueError(
            f"widths {widths} gives {len(widths)} levels; give 2 to {MAX_LEVELS} (an encoder "
            "and a decoder need two levels at least)"
        )


@node("segmentation.train", version=1, check=_check_train)
def train(
    train: LabelledScenes,
    *,
    widths: Annotated[list[Width], Field(min_length=2, max_length=MAX_LEVELS)] = [8, 16, 32],  # noqa: B006
    convs: Annotated[int, Field(ge=1, le=4)] = 2,
    epochs: Epochs = 120,
    batch_size: Count = 4,
    crop: Annotated[int, Field(ge=0, le=512)] = 32,
    learning_rate: Annotated[Positive, Field(le=1)] = 0.004,
    weighting: Literal["none", "median_frequency"] = "median_frequency",
    augment: bool = True,
    seed: Seed = 0,
) -> Segmenter:
    """Train an encoder–decoder network with skip connections (U-Net) to label every
    pixel, minimising the per-pixel softmax cross-entropy by Adam.

    Level ``l`` of the encoder holds ``convs`` 3×3 convolutions of ``widths[l]`` filters
    with ReLU, a 2×2 max pooling between levels; the decoder doubles the resolution by
    2×2 transposed convolutions of stride 2, concatenates the encoder's activation of the
    same level (the skip connection that brings back the detail pooling lost), and
    applies ``convs`` 3×3 convolutions with ReLU; a 1×1 convolution scores the classes at
    every pixel. Each scene of a batch is cut to a random ``crop`` × ``crop`` window (the
    U-Net authors' tiles: many more steps for the same work; the network is fully
    convolutional, so it labels whole scenes after), and the batch is turned by a random
    multiple of 90° and mirrored at random when ``augment`` is set. Adam's step size is
    annealed on a cosine to 0.

    Parameters
    ----------
    train : LabelledScenes
        Scenes (N, H, W) and their labels; H and W multiples of 2^(levels - 1).
    widths : list of int
        Filters per level, 2 to 6 levels of 1 to 256.
    convs : int
        3×3 convolutions per level and side.
    epochs : int
        Passes over the training scenes.
    batch_size : int
        Scenes (windows) per step.
    crop : int
        Side of the window each training scene is cut to, a multiple of 2^(levels - 1)
        no larger than the scenes; 0 takes whole scenes.
    learning_rate : float
        Adam's step size η.
    weighting : {'none', 'median_frequency'}
        Class weights of the loss: equal, or median frequency balancing (rare classes
        count more).
    augment : bool
        Turn and mirror each batch at random.
    seed : int
        Seed of the initial weights, the batch order and the augmentation.

    Returns
    -------
    Segmenter
        The trained network, with its loss and pixel accuracy per epoch.

    References
    ----------
    .. [1] J. Long, E. Shelhamer, T. Darrell, "Fully convolutional networks for semantic
       segmentation", CVPR 2015.
    .. [2] O. Ronneberger, P. Fischer, T. Brox, "U-Net: convolutional networks for
       biomedical image segmentation", MICCAI 2015.
    .. [3] D. P. Kingma, J. Ba, "Adam: a method for stochastic optimization", ICLR 2015.
    """
    names = train.class_names
    net = build_unet(list(widths), len(names), convs)
    multiple = 2 ** (len(widths) - 1)
    side = train.images.shape[1:]
    if side[0] % multiple or side[1] % multiple:
        raise ValueError(
            f"the scenes are {side[0]}×{side[1]} but a {len(widths)}-level network needs "
            f"sides that are multiples of {multiple}: use fewer widths or other scenes"
        )
    if crop % multiple or crop > min(side):
        raise ValueError(
            f"crop {crop} must be a multiple of {multiple} (the network has {len(widths)} "
            f"levels) no larger than the {side[0]}×{side[1]} scenes, or 0 for whole scenes"
        )
    window = (crop, crop) if crop else side
    batch = min(batch_size, len(train))
    if batch * window[0] * window[1] > MAX_BATCH_PIXELS:
        raise ValueError(
            f"a batch of {batch} windows of {window[0]}×{window[1]} holds "
            f"{batch * window[0] * window[1]:,} "
            f"pixels, at most {MAX_BATCH_PIXELS:,}: lower batch_size"
        )
    weights, history, accuracy = fit_unet(
        net, train.images, train.labels,
        weights_per_class=class_weights(train.labels, len(names), weighting),
        epochs=epochs, batch_size=batch, learning_rate=learning_rate,
        augment=augment, seed=seed, crop=crop,
    )  # fmt: skip
    spec = json.dumps({"widths": list(widths), "convs": convs})
    return SegmenterModel(spec, weights, train.names, history, accuracy)


@node("segmentation.predict", version=1)
def predict(network: Segmenter, scenes: LabelledScenes) -> LabelledScenes:
    """Label every pixel of the scenes with the network's most probable class.

    Parameters
    ----------
    network : Segmenter
        A trained network.
    scenes : LabelledScenes
        Scenes whose sides are multiples of 2^(levels - 1); their own labels are not used.

    Returns
    -------
    LabelledScenes
        The same images with the predicted labels, :math:`\\arg\\max_k s_k(x)` at every
        pixel :math:`x`, and the network's class names.

    References
    ----------
    J. Long, E. Shelhamer, T. Darrell, "Fully convolutional networks for semantic
    segmentation", CVPR 2015.
    """
    if scenes.class_names != network.class_names:
        raise ValueError(
            f"the network labels {network.class_names} but the scenes name "
            f"{scenes.class_names}: train it on scenes of the same classes"
        )
    labels = network.scores(scenes.images).argmax(axis=3).astype(np.int32)
    return LabelledSceneSet(scenes.images, labels, network.names)
