"""The ``Segmenter`` port type: a trained U-Net (its widths, weights, class names and
training curve), checked when built.

A segmenter is a frozen dataclass (nothing pickled): ``architecture`` is JSON text
``{"widths": [8, 16, 32], "convs": 2}``, ``weights`` one float64 vector holding every
step's parameters in order (see ``_unet``), ``names`` the JSON list of the class names
(the background's first), ``history`` the mean training loss of each epoch and
``accuracy`` the training pixel accuracy of each epoch (the training curve).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np

from graphvision import PortValueError, RecordPort

from ._unet import UNet, build_unet

__all__ = [
    "MAX_LEVELS",
    "MAX_WIDTH",
    "Segmenter",
    "SegmenterModel",
    "SegmenterPort",
]

MAX_WIDTH = 256
"""Most filters of a level: a NumPy network trained on one core."""
MAX_LEVELS = 6
"""Most levels of the encoder (the input side must be a multiple of 2^(levels - 1))."""


@dataclass(frozen=True, eq=False)
class SegmenterModel:
    """A trained encoder–decoder network (see the module)."""

    architecture: str
    weights: np.ndarray
    names: str
    history: np.ndarray
    accuracy: np.ndarray

    @property
    def class_names(self) -> list[str]:
        return list(json.loads(self.names))

    def network(self) -> UNet:
        """The U-Net its architecture describes."""
        spec = json.loads(self.architecture)
        return build_unet(list(spec["widths"]), len(self.class_names), int(spec["convs"]))

    def scores(self, images: np.ndarray, batch: int = 16) -> np.ndarray:
        """Class scores (N, H, W, K) for images (N, H, W) whose sides are multiples of
        2^(levels - 1), batch by batch with one BLAS thread."""
        from graphvision import one_blas_thread

        net = self.network()
        multiple = 2 ** (net.levels - 1)
        if images.shape[1] % multiple or images.shape[2] % multiple:
            raise ValueError(
                f"the network has {net.levels} levels, so a scene's sides must be multiples "
                f"of {multiple}; got {images.shape[1]}×{images.shape[2]}"
            )
        weights = self.weights.astype(np.float32)
        x = np.asarray(images, np.float32)[..., None]
        with one_blas_thread():
            out = [
                net.forward(weights, x[start : start + batch])[0]
                for start in range(0, len(x), batch)
            ]
        return np.concatenate(out)


class SegmenterPort(RecordPort):
    """A :class:`SegmenterModel`: widths within bounds, finite float64 weights of the size
    they need, at least two class names, one loss and one accuracy per epoch."""

    value_class = SegmenterModel

    @classmethod
    def validate(cls, value: Any) -> SegmenterModel:
        value = super().validate(value)
        try:
            spec = json.loads(value.architecture)
            widths, convs = list(spec["widths"]), int(spec["convs"])
            names = json.loads(value.names)
        except (ValueError, KeyError, TypeError) as error:
            raise PortValueError(f"Segmenter architecture or names are invalid: {error}") from None
        if not 2 <= len(widths) <= MAX_LEVELS or not all(1 <= w <= MAX_WIDTH for w in widths):
            raise PortValueError(
                f"Segmenter widths must be 2 to {MAX_LEVELS} counts in [1, {MAX_WIDTH}]"
            )
        if not isinstance(names, list) or len(names) < 2:
            raise PortValueError("Segmenter names must list the background and a class")
        size = build_unet(widths, len(names), convs).size
        weights = value.weights
        if not isinstance(weights, np.ndarray) or weights.dtype != np.float64:
            raise PortValueError("Segmenter 'weights' must be a float64 vector")
        if weights.shape != (size,):
            raise PortValueError(
                f"Segmenter 'weights' must hold {size} values, got {weights.shape}"
            )
        if not np.isfinite(weights).all():
            raise PortValueError("Segmenter 'weights' must be finite")
        for name in ("history", "accuracy"):
            column = getattr(value, name)
            if not isinstance(column, np.ndarray) or column.dtype != np.float64 or column.ndim != 1:
                raise PortValueError(f"Segmenter '{name}' must be a float64 vector")
        return value

    @classmethod
    def summary(cls, value: SegmenterModel) -> str:
        spec = json.loads(value.architecture)
        return (
            f"Segmenter U-Net widths {spec['widths']} × {spec['convs']} convolutions, "
            f"{len(value.class_names)} classes ({len(value.weights)} weights)"
        )


Segmenter = Annotated[SegmenterModel, SegmenterPort]
