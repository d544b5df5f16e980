"""The layers of a small convolutional network, forward and backward, in NumPy (seed: "A
modern approach": convolutional, ReLU, pooling and fully connected layers).

Activations are float64 arrays ``(N, C, H, W)`` (images) or ``(N, D)`` (vectors). A
layer is described by a short text (``"conv 16x3"``, ``"relu"``, ``"maxpool 2"``,
``"dense 10"``); :func:`parse_layer` turns it into a :class:`Layer`, which knows its
output shape, its parameter shapes, and its forward and backward passes. A convolution
is one matrix product over the image's patches (im2col), so the work is BLAS's.

Backward passes take the gradient of the loss with respect to the layer's output and
return the gradient with respect to its input and to each of its parameters.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

__all__ = [
    "Layer",
    "parse_layer",
    "softmax_cross_entropy",
]

Shape = tuple[int, ...]
_PATTERNS = {
    "conv": re.compile(r"conv (\d+)x(\d+)(?: pad (\d+))?"),
    "relu": re.compile(r"relu"),
    "maxpool": re.compile(r"maxpool (\d+)"),
    "dense": re.compile(r"dense (\d+)"),
}
LAYER_SYNTAX = "'conv FxK' [pad P], 'relu', 'maxpool S' or 'dense U'"
MAX_UNITS = 4096
"""Most filters of a convolution or units of a dense layer: a NumPy network trained on one
core; 4,096 is the width of AlexNet's and VGG's fully connected layers."""
MAX_KERNEL = 31
"""Largest side of a convolution kernel (and largest padding is one less): the im2col
matrix grows with its square."""
MAX_POOL = 32
"""Largest side of a max-pooling cell."""


@dataclass(frozen=True)
class Layer:
    """One layer: ``kind`` (conv, relu, maxpool, dense) and its integer settings: ``units``
    (filters of a convolution, outputs of a dense layer), ``size`` (kernel or pooling side)
    and ``pad`` (zeros around a convolution's input). ``input_gradient`` False spares a
    first layer the gradient with respect to its input (nothing uses it; an empty array
    takes its place)."""

    kind: str
    units: int = 0
    size: int = 0
    pad: int = 0
    input_gradient: bool = True

    @property
    def text(self) -> str:
        """The layer as written in a layer list."""
        if self.kind == "conv":
            return f"conv {self.units}x{self.size} pad {self.pad}"
        if self.kind == "maxpool":
            return f"maxpool {self.size}"
        if self.kind == "dense":
            return f"dense {self.units}"
        return self.kind

    def output_shape(self, shape: Shape) -> Shape:
        """The shape of one output for one input of ``shape`` (without the batch axis), or
        ValueError saying why the input does not fit this layer."""
        if self.kind == "relu":
            return shape
        if self.kind == "dense":
            return (self.units,)
        if len(shape) != 3:
            raise ValueError(f"takes a (C, H, W) image but its input is a vector {shape}")
        channels, height, width = shape
        if self.kind == "conv":
            rows, cols = height + 2 * self.pad - self.size + 1, width + 2 * self.pad - self.size + 1
            if rows < 1 or cols < 1:
                raise ValueError(
                    f"its {self.size}×{self.size} kernel does not fit its {height}×{width} "
                    f"input padded by {self.pad}"
                )
            return (self.units, rows, cols)
        if height < self.size or width < self.size:
            raise ValueError(f"pools {self.size}×{self.size} cells of a {height}×{width} input")
        return (channels, height // self.size, width // self.size)

    def parameter_shapes(self, shape: Shape) -> list[Shape]:
        """Shapes of the weights and the bias for an input of ``shape`` (none for ReLU and
        pooling)."""
        if self.kind == "conv":
            return [(self.units, shape[0], self.size, self.size), (self.units,)]
        if self.kind == "dense":
            return [(int(np.prod(shape)), self.units), (self.units,)]
        return []

    def forward(self, x: np.ndarray, params: list[np.ndarray]) -> tuple[np.ndarray, Any]:
        """The output for a batch ``x`` and what the backward pass needs."""
        return _FORWARD[self.kind](self, x, params)

    def backward(
        self, grad: np.ndarray, saved: Any, params: list[np.ndarray]
    ) -> tuple[np.ndarray, list[np.ndarray]]:
        """The gradients with respect to the input and to each parameter."""
        return _BACKWARD[self.kind](self, grad, saved, params)


def parse_layer(text: str) -> Layer:
    """A layer from its text, e.g. ``"conv 16x3"`` (16 filters 3×3, padded by 1 so that
    the size is kept), ``"conv 8x5 pad 0"``, ``"relu"``, ``"maxpool 2"``, ``"dense 10"``.

    Numbers are bounded for a NumPy network on one core: at most ``MAX_UNITS`` (4,096)
    filters or units, kernels up to ``MAX_KERNEL`` (31) with a padding below the kernel,
    pooling cells up to ``MAX_POOL`` (32); ValueError names the layer and the bound. The
    whole network's size, which needs the input shape, is bounded when it is built
    (``build_architecture``)."""
    spec = " ".join(text.split()).lower()
    for kind, pattern in _PATTERNS.items():
        found = pattern.fullmatch(spec)
        if found is None:
            continue
        numbers = [int(group) for group in found.groups() if group is not None]
        if any(number < 1 for number in numbers[:2]):
            raise ValueError(f"'{text}': sizes and counts must be at least 1")
        _check_maxima(text, kind, numbers)
        if kind == "conv":
            pad = numbers[2] if len(numbers) > 2 else numbers[1] // 2
            return Layer(kind, units=numbers[0], size=numbers[1], pad=pad)
        if kind == "maxpool":
            return Layer(kind, size=numbers[0])
        if kind == "dense":
            return Layer(kind, units=numbers[0])
        return Layer(kind)
    raise ValueError(f"'{text}' is not a layer; write {LAYER_SYNTAX}")


def _check_maxima(text: str, kind: str, numbers: list[int]) -> None:
    """ValueError naming the layer's text when one of its numbers exceeds its maximum."""
    bounds = {
        "conv": [("filters", MAX_UNITS), ("kernel size", MAX_KERNEL), ("padding", MAX_KERNEL - 1)],
        "maxpool": [("pooling size", MAX_POOL)],
        "dense": [("units", MAX_UNITS)],
    }.get(kind, [])
    for (what, most), number in zip(bounds, numbers, strict=False):
        if number > most:
            raise ValueError(f"'{text}': {what} {number} exceeds the maximum {most}")


def _patches(layer: Layer, x: np.ndarray) -> np.ndarray:
    """im2col: every k×k patch of every channel as one row, (N·H'·W', C·k·k)."""
    padded = np.pad(x, ((0, 0), (0, 0), (layer.pad, layer.pad), (layer.pad, layer.pad)))
    windows = sliding_window_view(padded, (layer.size, layer.size), axis=(2, 3))
    count, _, rows, cols = windows.shape[:4]
    return windows.transpose(0, 2, 3, 1, 4, 5).reshape(count * rows * cols, -1)


def _conv_forward(layer: Layer, x: np.ndarray, params: list[np.ndarray]) -> tuple[Any, Any]:
    weights, bias = params
    rows = x.shape[2] + 2 * layer.pad - layer.size + 1
    cols = x.shape[3] + 2 * layer.pad - layer.size + 1
    patches = _patches(layer, x)
    out = patches @ weights.reshape(layer.units, -1).T + bias
    return out.reshape(len(x), rows, cols, layer.units).transpose(0, 3, 1, 2), (x.shape, patches)


def _conv_backward(
    layer: Layer, grad: np.ndarray, saved: Any, params: list[np.ndarray]
) -> tuple[np.ndarray, list[np.ndarray]]:
    weights, _ = params
    shape, patches = saved
    count, channels, height, width = shape
    rows, cols = grad.shape[2:]
    flat = grad.transpose(0, 2, 3, 1).reshape(-1, layer.units)
    d_weights = (flat.T @ patches).reshape(weights.shape)
    d_bias = flat.sum(axis=0)
    if not layer.input_gradient:
        return np.zeros(0, grad.dtype), [d_weights, d_bias]
    size, pad = layer.size, layer.pad
    d_patches = (flat @ weights.reshape(layer.units, -1)).reshape(
        count, rows, cols, channels, size, size
    )
    by_offset = np.ascontiguousarray(d_patches.transpose(4, 5, 0, 3, 1, 2))
    d_padded = np.zeros((count, channels, height + 2 * pad, width + 2 * pad), grad.dtype)
    for i in range(size):  # col2im: k² strided additions
        for j in range(size):
            d_padded[:, :, i : i + rows, j : j + cols] += by_offset[i, j]
    return d_padded[:, :, pad : pad + height, pad : pad + width], [d_weights, d_bias]


def _relu_forward(layer: Layer, x: np.ndarray, params: list[np.ndarray]) -> tuple[Any, Any]:
    positive = x > 0
    return x * positive, positive


def _relu_backward(
    layer: Layer, grad: np.ndarray, saved: Any, params: list[np.ndarray]
) -> tuple[np.ndarray, list[np.ndarray]]:
    return grad * saved, []


def _pool_forward(layer: Layer, x: np.ndarray, params: list[np.ndarray]) -> tuple[Any, Any]:
    s = layer.size
    count, channels, height, width = x.shape
    rows, cols = height // s, width // s
    cells = x[:, :, : rows * s, : cols * s].reshape(count, channels, rows, s, cols, s)
    cells = cells.transpose(0, 1, 2, 4, 3, 5).reshape(count, channels, rows, cols, s * s)
    winner = cells.argmax(axis=4)  # the first maximum of a cell takes the whole gradient
    out = np.take_along_axis(cells, winner[..., None], axis=4)[..., 0]
    return out, (x.shape, winner)


def _pool_backward(
    layer: Layer, grad: np.ndarray, saved: Any, params: list[np.ndarray]
) -> tuple[np.ndarray, list[np.ndarray]]:
    s = layer.size
    shape, winner = saved
    count, channels = shape[:2]
    rows, cols = grad.shape[2:]
    cells = np.zeros((count, channels, rows, cols, s * s), grad.dtype)
    np.put_along_axis(cells, winner[..., None], grad[..., None], axis=4)
    cells = cells.reshape(count, channels, rows, cols, s, s).transpose(0, 1, 2, 4, 3, 5)
    d_x = np.zeros(shape, grad.dtype)
    d_x[:, :, : rows * s, : cols * s] = cells.reshape(count, channels, rows * s, cols * s)
    return d_x, []


def _dense_forward(layer: Layer, x: np.ndarray, params: list[np.ndarray]) -> tuple[Any, Any]:
    weights, bias = params
    flat = x.reshape(len(x), -1)
    return flat @ weights + bias, (x.shape, flat)


def _dense_backward(
    layer: Layer, grad: np.ndarray, saved: Any, params: list[np.ndarray]
) -> tuple[np.ndarray, list[np.ndarray]]:
    weights, _ = params
    shape, flat = saved
    return (grad @ weights.T).reshape(shape), [flat.T @ grad, grad.sum(axis=0)]


_FORWARD = {
    "conv": _conv_forward,
    "relu": _relu_forward,
    "maxpool": _pool_forward,
    "dense": _dense_forward,
}
_BACKWARD = {
    "conv": _conv_backward,
    "relu": _relu_backward,
    "maxpool": _pool_backward,
    "dense": _dense_backward,
}


def softmax_cross_entropy(scores: np.ndarray, targets: np.ndarray) -> tuple[float, np.ndarray]:
    r"""Mean cross-entropy of the softmax of ``scores`` (N, K) against class indices
    ``targets`` (N,), and its gradient with respect to the scores:

    .. math::
        p_{nk} = \frac{e^{s_{nk}}}{\sum_j e^{s_{nj}}},\quad
        L = -\frac{1}{N}\sum_n \log p_{n y_n},\quad
        \frac{\partial L}{\partial s_{nk}} = \frac{p_{nk} - [k = y_n]}{N}
    """
    shifted = scores - scores.max(axis=1, keepdims=True)
    log_p = shifted - np.log(np.exp(shifted).sum(axis=1, keepdims=True))
    rows = np.arange(len(scores))
    loss = -float(log_p[rows, targets].mean())
    grad = np.exp(log_p)
    grad[rows, targets] -= 1
    return loss, grad / len(scores)
