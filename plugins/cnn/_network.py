"""The ``Network`` port type: a layer list and its weights, checked when built.

A network is a frozen dataclass (nothing pickled): ``architecture`` is JSON text
``{"input": [C, H, W], "layers": ["conv 16x3 pad 1", "relu", ...]}``, ``weights`` one
float64 vector holding every layer's parameters in order (weights then bias, C order),
``classes`` the label each output unit stands for, ``history`` the mean training loss of
each epoch, ``accuracy`` the training accuracy of each epoch and ``held_out_accuracy``
that of the held-out samples after each epoch (empty when none were given; both empty
in a network trained before they were recorded). Building a network chains the layer
shapes and refuses, naming the layer, one whose input does not fit.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np

from graphvision import PortValueError, RecordPort

from ._layers import Layer, parse_layer

__all__ = [
    "MAX_BATCH_VALUES",
    "MAX_SAMPLE_VALUES",
    "MAX_WEIGHTS",
    "Architecture",
    "Network",
    "NetworkModel",
    "NetworkPort",
    "build_architecture",
    "initial_weights",
]

MAX_WEIGHTS = 10_000_000
"""Most weights of a network (80 MB in float64, as much again for the gradient and the
momentum): a NumPy network trained on one core of this machine."""
MAX_SAMPLE_VALUES = 2**25
"""Most values of the largest array one input makes in a forward pass (a layer's output
or a convolution's im2col matrix): 256 MB in float64."""
MAX_BATCH_VALUES = 2**27
"""Most values of that array over a training batch: 512 MB in float32."""


@dataclass(frozen=True)
class Architecture:
    """Parsed layers, the shape entering each layer (and the output shape last), and the
    shapes of each layer's parameters."""

    layers: list[Layer]
    shapes: list[tuple[int, ...]]
    parameter_shapes: list[list[tuple[int, ...]]]

    @property
    def size(self) -> int:
        """The number of weights."""
        return sum(int(np.prod(shape)) for shapes in self.parameter_shapes for shape in shapes)

    @property
    def sample_values(self) -> int:
        """The values of the largest array one input makes in a forward pass: a layer's
        output, or a convolution's im2col matrix (output pixels × C·k·k)."""
        return max(self.layer_values())

    def layer_values(self) -> list[int]:
        """Per layer, the values of the largest array it makes for one input."""
        pairs = zip(self.layers, self.shapes[:-1], strict=True)
        return [_layer_values(layer, shape) for layer, shape in pairs]

    def split(self, weights: np.ndarray) -> list[list[np.ndarray]]:
        """Views of the flat ``weights`` vector, one list of arrays per layer."""
        params, start = [], 0
        for shapes in self.parameter_shapes:
            arrays = []
            for shape in shapes:
                stop = start + int(np.prod(shape))
                arrays.append(weights[start:stop].reshape(shape))
                start = stop
            params.append(arrays)
        return params

    def forward(
        self, weights: np.ndarray, x: np.ndarray, keep: bool = False
    ) -> tuple[np.ndarray, list[Any]]:
        """The scores of the last layer for a batch ``x`` (and, with ``keep``, what the
        backward pass needs)."""
        saved = []
        for layer, params in zip(self.layers, self.split(weights), strict=True):
            x, memo = layer.forward(x, params)
            if keep:
                saved.append(memo)
        return x, saved

    def backward(self, weights: np.ndarray, grad: np.ndarray, saved: list[Any]) -> np.ndarray:
        """The gradient of the loss with respect to ``weights`` (flat, same order), given
        its gradient ``grad`` with respect to the scores."""
        params = self.split(weights)
        pieces: list[list[np.ndarray]] = []
        for layer, memo, layer_params in zip(
            reversed(self.layers), reversed(saved), reversed(params), strict=True
        ):
            grad, d_params = layer.backward(grad, memo, layer_params)
            pieces.append(d_params)
        flat = [d.ravel() for d_params in reversed(pieces) for d in d_params]
        return np.concatenate(flat) if flat else np.zeros(0)


def build_architecture(input_shape: tuple[int, ...], layers: list[str]) -> Architecture:
    """Parse ``layers`` and chain their shapes from ``input_shape`` (C, H, W), or raise
    ValueError naming the layer (its index and text) that does not fit, or saying how
    large the network would be when it holds more than ``MAX_WEIGHTS`` weights or one
    input makes more than ``MAX_SAMPLE_VALUES`` values. The first layer computes no
    gradient with respect to the network's input."""
    if not layers:
        raise ValueError("a network needs at least one layer")
    parsed, shapes, parameter_shapes = [], [tuple(input_shape)], []
    for index, text in enumerate(layers):
        try:
            layer = parse_layer(text)
            parameter_shapes.append(layer.parameter_shapes(shapes[-1]))
            shapes.append(layer.output_shape(shapes[-1]))
        except ValueError as error:
            raise ValueError(
                f"layer {index} '{text}' does not chain: {error} (input {shapes[-1]})"
            ) from None
        parsed.append(layer)
    parsed[0] = dataclasses.replace(parsed[0], input_gradient=False)
    architecture = Architecture(parsed, shapes, parameter_shapes)
    _check_size(architecture, layers)
    return architecture


def _layer_values(layer: Layer, shape: tuple[int, ...]) -> int:
    """The values of the largest array ``layer`` makes for one input of ``shape``."""
    out = layer.output_shape(shape)
    values = int(np.prod(out))
    if layer.kind == "conv":
        values = max(values, int(np.prod(out[1:])) * shape[0] * layer.size**2)
    return max(values, int(np.prod(shape)))


def _check_size(architecture: Architecture, texts: list[str]) -> None:
    """ValueError naming the largest layer when the network holds more than
    ``MAX_WEIGHTS`` weights, or one input makes more than ``MAX_SAMPLE_VALUES`` values."""
    weights = [sum(int(np.prod(s)) for s in shapes) for shapes in architecture.parameter_shapes]
    if sum(weights) > MAX_WEIGHTS:
        index = int(np.argmax(weights))
        raise ValueError(
            f"the network would hold {sum(weights):,} weights ({sum(weights) * 8 / 2**30:.1f} "
            f"GiB) for its input {architecture.shapes[0]}, at most {MAX_WEIGHTS:,}; layer "
            f"{index} '{texts[index]}' alone holds {weights[index]:,}: use fewer filters or units"
        )
    values = architecture.layer_values()
    if max(values) > MAX_SAMPLE_VALUES:
        index = int(np.argmax(values))
        raise ValueError(
            f"layer {index} '{texts[index]}' would make {values[index]:,} values "
            f"({values[index] * 8 / 2**30:.1f} GiB) for one input {architecture.shapes[0]}, "
            f"at most {MAX_SAMPLE_VALUES:,}: use fewer filters, a smaller kernel or an "
            "earlier pooling"
        )


def initial_weights(architecture: Architecture, seed: int) -> np.ndarray:
    r"""He initialisation: weights drawn from :math:`\mathcal{N}(0, 2 / n_\mathrm{in})`
    (n_in the inputs of one output unit), biases zero; seeded.

    References
    ----------
    K. He et al., "Delving deep into rectifiers", ICCV 2015.
    """
    rng = np.random.default_rng(seed)
    pieces = []
    for shapes in architecture.parameter_shapes:
        for shape in shapes:
            if len(shape) == 1:
                pieces.append(np.zeros(shape[0]))
                continue
            fan_in = int(np.prod(shape[1:])) if len(shape) == 4 else shape[0]
            pieces.append(rng.normal(0, np.sqrt(2 / fan_in), int(np.prod(shape))))
    return np.concatenate(pieces) if pieces else np.zeros(0)


@dataclass(frozen=True, eq=False)
class NetworkModel:
    """A trained network (see the module docstring)."""

    architecture: str
    weights: np.ndarray
    classes: np.ndarray
    history: np.ndarray
    accuracy: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    held_out_accuracy: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))

    def parsed(self) -> Architecture:
        """The architecture, parsed and chained."""
        spec = json.loads(self.architecture)
        return build_architecture(tuple(spec["input"]), spec["layers"])

    def scores(self, images: np.ndarray, batch: int = 512) -> np.ndarray:
        """The last layer's outputs for images (N, H, W) or (N, C, H, W), batch by batch."""
        architecture = self.parsed()
        x = np.asarray(images, np.float64)
        if x.ndim == 3:
            x = x[:, None]
        if x.shape[1:] != architecture.shapes[0]:
            raise ValueError(
                f"the network takes inputs {architecture.shapes[0]} (C, H, W), got {x.shape[1:]}"
            )
        from graphvision import one_blas_thread

        with one_blas_thread():
            out = [
                architecture.forward(self.weights, x[start : start + batch])[0]
                for start in range(0, len(x), batch)
            ]
        return np.concatenate(out) if out else np.zeros((0, architecture.shapes[-1][0]))


class NetworkPort(RecordPort):
    """A :class:`NetworkModel`: layers that chain, finite float64 weights of the size they
    need, one class label (int64) per output unit."""

    value_class = NetworkModel

    @classmethod
    def validate(cls, value: Any) -> NetworkModel:
        value = super().validate(value)
        try:
            spec = json.loads(value.architecture)
            architecture = build_architecture(tuple(spec["input"]), list(spec["layers"]))
        except (ValueError, KeyError, TypeError) as error:
            raise PortValueError(f"Network architecture is invalid: {error}") from None
        weights = value.weights
        if not isinstance(weights, np.ndarray) or weights.dtype != np.float64:
            raise PortValueError("Network 'weights' must be a float64 vector")
        if weights.shape != (architecture.size,):
            raise PortValueError(
                f"Network 'weights' must hold {architecture.size} values for its layers, "
                f"got {weights.shape}"
            )
        if not np.isfinite(weights).all():
            raise PortValueError("Network 'weights' must be finite")
        classes = value.classes
        if not isinstance(classes, np.ndarray) or classes.dtype != np.int64:
            raise PortValueError("Network 'classes' must be an int64 vector")
        if architecture.shapes[-1] != (len(classes),):
            raise PortValueError(
                f"the network's last layer gives {architecture.shapes[-1]} outputs for "
                f"{len(classes)} classes"
            )
        for name in ("accuracy", "held_out_accuracy"):
            curve = getattr(value, name)
            if not isinstance(curve, np.ndarray) or curve.ndim != 1:
                raise PortValueError(f"Network '{name}' must be a vector (one value per epoch)")
        return value

    @classmethod
    def preview(cls, value: NetworkModel) -> np.ndarray | None:
        """The first convolution's filters (first input channel), each stretched to [0, 1];
        None when the network starts with another layer."""
        from ..recognition._types import mosaic

        architecture = value.parsed()
        if architecture.layers[0].kind != "conv":
            return None
        filters = architecture.split(value.weights)[0][0][:, 0]
        side = max(filters.shape[1], 1)
        scale = max(1, 32 // side)  # a 3×3 filter is drawn 30×30
        return mosaic(np.kron(filters, np.ones((scale, scale))))

    @classmethod
    def summary(cls, value: NetworkModel) -> str:
        spec = json.loads(value.architecture)
        return f"Network {' → '.join(spec['layers'])} ({len(value.weights)} weights)"


Network = Annotated[NetworkModel, NetworkPort]
