"""A small convolutional network in NumPy (seed: "A modern approach"): convolution (im2col
and BLAS), ReLU, max pooling, fully connected layers and the softmax cross-entropy, with
their backward passes, trained by mini-batch SGD with momentum, seeded. A trained network
is the ``Network`` port type (layer list + weights), so it is cached and crosses
processes; ``cnn.digits`` gives scikit-learn's 8×8 digits.
"""

from ._digits import digits, load_digits_images
from ._draw import draw_predictions
from ._layers import Layer, parse_layer, softmax_cross_entropy
from ._network import (
    Architecture,
    Network,
    NetworkModel,
    NetworkPort,
    build_architecture,
    initial_weights,
)
from ._train import accuracy, check_layer_texts, fit_network, predict, train

__all__ = [
    "Architecture",
    "Layer",
    "Network",
    "NetworkModel",
    "NetworkPort",
    "accuracy",
    "build_architecture",
    "check_layer_texts",
    "digits",
    "draw_predictions",
    "fit_network",
    "initial_weights",
    "load_digits_images",
    "parse_layer",
    "predict",
    "softmax_cross_entropy",
    "train",
]
