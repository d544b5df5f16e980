"""An encoder–decoder network with skip connections (U-Net), forward and backward, in NumPy.

The encoder is ``len(widths)`` levels of 3×3 convolutions with ReLU (``widths[l]``
filters at level ``l``), a 2×2 max pooling between two levels; the decoder climbs back,
each level doubling the resolution by a 2×2 transposed convolution of stride 2
("up-convolution"), concatenating the encoder's activation of the same level (the skip
connection) and applying 3×3 convolutions with ReLU again; a 1×1 convolution gives one
score per class at every pixel.

Activations are (N, H, W, C) arrays (channels last), so that a convolution's patches are
nine strided copies and its output one matrix product (BLAS), without the transposes a
channels-first layout needs: on 64×64 scenes this runs several times faster than the
``cnn`` family's channels-first layers. The network is a list of :class:`Step` s over
named activations: the forward pass runs them in order and the backward pass in
reverse, adding the gradients of an activation used twice (a skip). Weights are one flat
float vector, each parametric step's weights then bias, in step order.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "Conv",
    "MaxPool",
    "Relu",
    "Step",
    "UNet",
    "UpConv",
    "build_unet",
    "pixel_cross_entropy",
]

Params = list[np.ndarray]
INPUT_MEAN = 0.5
"""Subtracted from the images (in [0, 1]) before the first layer, so they are centred."""


@dataclass(frozen=True)
class Conv:
    r"""A K×K convolution (K odd, zero padding K // 2, so the size is kept):

    .. math:: y_{i,j,o} = \beta_o + \sum_{a,b,c} x_{i+a-K/2,\,j+b-K/2,\,c}\, W_{a,b,c,o}

    computed as one product of the patches (N·H·W, K·K·C) with the weights (K, K, C,
    units). ``input_gradient`` False spares the first layer its input's gradient."""

    units: int
    size: int = 3
    input_gradient: bool = True

    def parameter_shapes(self, channels: int) -> list[tuple[int, ...]]:
        return [(self.size, self.size, channels, self.units), (self.units,)]

    def fan_in(self, channels: int) -> int:
        return self.size * self.size * channels

    def forward(self, x: np.ndarray, params: Params) -> tuple[np.ndarray, Any]:
        weights, bias = params
        count, height, width, channels = x.shape
        k, pad = self.size, self.size // 2
        if k == 1:
            cols = x.reshape(-1, channels)
        else:
            padded = np.pad(x, ((0, 0), (pad, pad), (pad, pad), (0, 0)))
            patches = np.empty((count, height, width, k, k, channels), x.dtype)
            for a in range(k):
                for b in range(k):
                    patches[:, :, :, a, b] = padded[:, a : a + height, b : b + width]
            cols = patches.reshape(-1, k * k * channels)
        out = cols @ weights.reshape(-1, self.units) + bias
        return out.reshape(count, height, width, self.units), (x.shape, cols)

    def backward(self, grad: np.ndarray, saved: Any, params: Params) -> tuple[np.ndarray, Params]:
        weights, _ = params
        shape, cols = saved
        count, height, width, channels = shape
        flat = grad.reshape(-1, self.units)
        d_weights = (cols.T @ flat).reshape(weights.shape)
        d_bias = flat.sum(axis=0)
        if not self.input_gradient:
            return np.zeros(0, grad.dtype), [d_weights, d_bias]
        d_cols = flat @ weights.reshape(-1, self.units).T
        k, pad = self.size, self.size // 2
        if k == 1:
            return d_cols.reshape(shape), [d_weights, d_bias]
        d_patches = d_cols.reshape(count, height, width, k, k, channels)
        padded = np.zeros((count, height + 2 * pad, width + 2 * pad, channels), grad.dtype)
        for a in range(k):  # col2im: K² strided additions
            for b in range(k):
                padded[:, a : a + height, b : b + width] += d_patches[:, :, :, a, b]
        return padded[:, pad : pad + height, pad : pad + width], [d_weights, d_bias]


@dataclass(frozen=True)
class Relu:
    """The rectifier max(x, 0)."""

    def parameter_shapes(self, channels: int) -> list[tuple[int, ...]]:
        return []

    def forward(self, x: np.ndarray, params: Params) -> tuple[np.ndarray, Any]:
        positive = x > 0
        return x * positive, positive

    def backward(self, grad: np.ndarray, saved: Any, params: Params) -> tuple[np.ndarray, Params]:
        return grad * saved, []


@dataclass(frozen=True)
class MaxPool:
    """2×2 max pooling of stride 2 (the height and width must be even); the first
    maximum of a cell takes its whole gradient."""

    def parameter_shapes(self, channels: int) -> list[tuple[int, ...]]:
        return []

    def forward(self, x: np.ndarray, params: Params) -> tuple[np.ndarray, Any]:
        count, height, width, channels = x.shape
        cells = x.reshape(count, height // 2, 2, width // 2, 2, channels)
        cells = cells.transpose(0, 1, 3, 5, 2, 4).reshape(*cells.shape[:2], width // 2, -1, 4)
        winner = cells.argmax(axis=4)
        out = np.take_along_axis(cells, winner[..., None], axis=4)[..., 0]
        return out, (x.shape, winner)

    def backward(self, grad: np.ndarray, saved: Any, params: Params) -> tuple[np.ndarray, Params]:
        (count, height, width, channels), winner = saved
        cells = np.zeros((*grad.shape, 4), grad.dtype)
        np.put_along_axis(cells, winner[..., None], grad[..., None], axis=4)
        cells = cells.reshape(count, height // 2, width // 2, channels, 2, 2)
        return cells.transpose(0, 1, 4, 2, 5, 3).reshape(count, height, width, channels), []


@dataclass(frozen=True)
class UpConv:
    r"""A transposed convolution with a 2×2 kernel and stride 2 (U-Net's "up-convolution";
    Long et al.'s "backwards convolution" with kernel = stride): every input pixel
    spreads over its own 2×2 output cell,

    .. math:: y_{2i+a,\,2j+b,\,o} = \beta_o + \sum_c x_{i,j,c}\, W_{c,a,b,o},
       \qquad a, b \in \{0, 1\},

    so the output is twice as high and wide, with ``units`` channels. Weights are
    (C, 2, 2, units), the bias (units,)."""

    units: int

    def parameter_shapes(self, channels: int) -> list[tuple[int, ...]]:
        return [(channels, 2, 2, self.units), (self.units,)]

    def fan_in(self, channels: int) -> int:
        return channels  # an output pixel sees one input pixel's channels

    def forward(self, x: np.ndarray, params: Params) -> tuple[np.ndarray, Any]:
        weights, bias = params
        count, height, width, channels = x.shape
        flat = x.reshape(-1, channels)
        out = (flat @ weights.reshape(channels, -1)).reshape(count, height, width, 2, 2, -1)
        out = out.transpose(0, 1, 3, 2, 4, 5).reshape(count, 2 * height, 2 * width, self.units)
        return out + bias, (x.shape, flat)

    def backward(self, grad: np.ndarray, saved: Any, params: Params) -> tuple[np.ndarray, Params]:
        weights, _ = params
        (count, height, width, channels), flat = saved
        cells = grad.reshape(count, height, 2, width, 2, self.units)
        cells = cells.transpose(0, 1, 3, 2, 4, 5).reshape(-1, 4 * self.units)
        d_weights = (flat.T @ cells).reshape(weights.shape)
        d_x = (cells @ weights.reshape(channels, -1).T).reshape(count, height, width, channels)
        return d_x, [d_weights, grad.sum(axis=(0, 1, 2))]


Op = Conv | Relu | MaxPool | UpConv


@dataclass(frozen=True)
class Step:
    """One step: ``op`` (a layer, or None for the concatenation of ``inputs`` along the
    channels) reads the named activations ``inputs`` and writes ``output``; ``channels``
    is the channel count of its (first) input."""

    op: Op | None
    inputs: tuple[str, ...]
    output: str
    channels: int

    def parameter_shapes(self) -> list[tuple[int, ...]]:
        return [] if self.op is None else self.op.parameter_shapes(self.channels)


@dataclass(frozen=True)
class UNet:
    """The steps of a U-Net and its number of classes (see the module)."""

    steps: list[Step]
    classes: int
    levels: int

    @property
    def parameter_shapes(self) -> list[list[tuple[int, ...]]]:
        return [step.parameter_shapes() for step in self.steps]

    @property
    def size(self) -> int:
        """The number of weights."""
        return sum(int(np.prod(s)) for shapes in self.parameter_shapes for s in shapes)

    def split(self, weights: np.ndarray) -> list[Params]:
        """Views of the flat ``weights``, one list of arrays per step."""
        params, start = [], 0
        for shapes in self.parameter_shapes:
            arrays = []
            for shape in shapes:
                stop = start + int(np.prod(shape))
                arrays.append(weights[start:stop].reshape(shape))
                start = stop
            params.append(arrays)
        return params

    def initial_weights(self, seed: int) -> np.ndarray:
        r"""He initialisation, :math:`\mathcal{N}(0, 2 / n_\mathrm{in})` (n_in the inputs
        of one output unit), biases zero; seeded.

        References
        ----------
        K. He et al., "Delving deep into rectifiers", ICCV 2015.
        """
        rng = np.random.default_rng(seed)
        pieces = []
        for step in self.steps:
            if not isinstance(step.op, Conv | UpConv):
                continue
            weights, bias = step.parameter_shapes()
            fan_in = step.op.fan_in(step.channels)
            pieces.append(rng.normal(0, np.sqrt(2 / fan_in), int(np.prod(weights))))
            pieces.append(np.zeros(bias[0]))
        return np.concatenate(pieces)

    def forward(
        self, weights: np.ndarray, x: np.ndarray, keep: bool = False
    ) -> tuple[np.ndarray, list[Any]]:
        """Scores (N, H, W, K) for images ``x`` (N, H, W, 1) in [0, 1] (centred by
        ``INPUT_MEAN`` first); with ``keep``, what the backward pass needs."""
        values = {"input": x - INPUT_MEAN}
        saved: list[Any] = []
        for step, params in zip(self.steps, self.split(weights), strict=True):
            inputs = [values[name] for name in step.inputs]
            if step.op is None:
                out, memo = np.concatenate(inputs, axis=3), [a.shape[3] for a in inputs]
            else:
                out, memo = step.op.forward(inputs[0], params)
            values[step.output] = out
            if keep:
                saved.append(memo)
        return values[self.steps[-1].output], saved

    def backward(self, weights: np.ndarray, grad: np.ndarray, saved: list[Any]) -> np.ndarray:
        """The gradient of the loss with respect to ``weights`` (flat, same order), given
        its gradient ``grad`` with respect to the scores."""
        params = self.split(weights)
        grads: dict[str, np.ndarray] = {self.steps[-1].output: grad}
        pieces: list[Params] = []
        for step, memo, step_params in zip(
            reversed(self.steps), reversed(saved), reversed(params), strict=True
        ):
            g = grads.pop(step.output)
            if step.op is None:
                parts = np.split(g, np.cumsum(memo)[:-1], axis=3)
                d_params: Params = []
            else:
                d_input, d_params = step.op.backward(g, memo, step_params)
                parts = [d_input]
            for name, part in zip(step.inputs, parts, strict=True):
                if name != "input":
                    grads[name] = grads[name] + part if name in grads else part
            pieces.append(d_params)
        flat = [d.ravel() for d_params in reversed(pieces) for d in d_params]
        return np.concatenate(flat)


def build_unet(widths: list[int], classes: int, convs: int = 2) -> UNet:
    """A U-Net with ``len(widths)`` levels (``widths[l]`` filters at level ``l``, each
    block ``convs`` 3×3 convolutions with ReLU) and ``classes`` output channels. The
    first convolution computes no gradient with respect to the image."""
    steps: list[Step] = []
    current, channels = "input", 1

    def block(prefix: str, units: int) -> None:
        nonlocal current, channels
        for k in range(convs):
            conv = Conv(units, 3, input_gradient=bool(steps))
            steps.append(Step(conv, (current,), f"{prefix}c{k}", channels))
            steps.append(Step(Relu(), (f"{prefix}c{k}",), f"{prefix}r{k}", units))
            current, channels = f"{prefix}r{k}", units

    skips = []
    for level, units in enumerate(widths):
        if level:
            steps.append(Step(MaxPool(), (current,), f"p{level}", channels))
            current = f"p{level}"
        block(f"e{level}", units)
        skips.append((current, channels))
    for level in range(len(widths) - 2, -1, -1):
        units = widths[level]
        steps.append(Step(UpConv(units), (current,), f"u{level}", channels))
        skip, skip_channels = skips[level]
        steps.append(Step(None, (f"u{level}", skip), f"k{level}", units))
        current, channels = f"k{level}", units + skip_channels
        block(f"d{level}", units)
    steps.append(Step(Conv(classes, 1), (current,), "scores", channels))
    return UNet(steps, classes, len(widths))


def pixel_cross_entropy(
    scores: np.ndarray, targets: np.ndarray, class_weights: np.ndarray
) -> tuple[float, np.ndarray]:
    r"""The weighted mean cross-entropy of the per-pixel softmax of ``scores`` (N, H, W, K)
    against the labels ``targets`` (N, H, W), and its gradient with respect to the scores:

    .. math::
        p_{k}(x) = \frac{e^{s_k(x)}}{\sum_j e^{s_j(x)}},\qquad
        L = -\frac{\sum_x w_{y(x)} \log p_{y(x)}(x)}{\sum_x w_{y(x)}},\qquad
        \frac{\partial L}{\partial s_k(x)} = w_{y(x)}\frac{p_k(x) - [k = y(x)]}{\sum_x w_{y(x)}}

    over every pixel :math:`x` of the batch (Long et al. 2015, section 3: the loss is a
    sum over the pixels of the last layer; the weights :math:`w` balance the classes).
    """
    classes = scores.shape[3]
    flat = scores.reshape(-1, classes)
    labels = targets.reshape(-1)
    shifted = flat - flat.max(axis=1, keepdims=True)
    log_p = shifted - np.log(np.exp(shifted).sum(axis=1, keepdims=True))
    rows = np.arange(len(labels))
    pixel_weight = class_weights[labels]
    total = float(pixel_weight.sum())
    loss = -float((pixel_weight * log_p[rows, labels]).sum()) / total
    grad = np.exp(log_p)
    grad[rows, labels] -= 1
    grad *= (pixel_weight / total)[:, None]
    return loss, grad.reshape(scores.shape)
