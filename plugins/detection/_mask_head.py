"""The mask branch of Mask R-CNN (He et al. 2017) on a trained Faster R-CNN: RoIAlign,
mask targets, and the small fully convolutional network's per-pixel training.

The branch's input for a box is the RoIAlign of the Faster R-CNN's feature map, with the
RoIAlign of the scene itself as one more channel (the ink's detail at full resolution),
``resolution`` × ``resolution`` cells; its output one mask logit map per class, of which
only the box's class is used (per-class masks, no competition between classes).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np

from graphvision import PortValueError, RecordPort

from ..cnn import Architecture, build_architecture

__all__ = [
    "MaskHead",
    "MaskHeadModel",
    "MaskHeadPort",
    "mask_targets",
    "paste_mask",
    "roi_align",
    "train_mask_network",
]


def roi_align(features: np.ndarray, xyxy: np.ndarray, stride: int, size: int) -> np.ndarray:
    r"""RoIAlign: each box (image pixels) divided into ``size`` × ``size`` bins, each bin the
    bilinear interpolation of ``features`` (C, h, w) at its centre, no rounding of the box:
    a bin centre :math:`x` in the image is :math:`x / s - 1/2` in the map of stride
    :math:`s` (cell centres at :math:`(i + 1/2) s`), clamped to the map. (R, C, size, size)
    float32.

    References
    ----------
    K. He, G. Gkioxari, P. Dollár and R. Girshick, "Mask R-CNN", ICCV 2017, section 3.
    """
    rows, cols = features.shape[1:]
    steps = (np.arange(size) + 0.5) / size
    xs = (xyxy[:, :1] + steps * (xyxy[:, 2:3] - xyxy[:, :1])) / stride - 0.5
    ys = (xyxy[:, 1:2] + steps * (xyxy[:, 3:4] - xyxy[:, 1:2])) / stride - 0.5
    xs, ys = np.clip(xs, 0, cols - 1), np.clip(ys, 0, rows - 1)
    x0, y0 = np.minimum(xs.astype(np.int64), cols - 2), np.minimum(ys.astype(np.int64), rows - 2)
    x0, y0 = np.maximum(x0, 0), np.maximum(y0, 0)
    fx, fy = xs - x0, ys - y0  # (R, size)
    x1, y1 = np.minimum(x0 + 1, cols - 1), np.minimum(y0 + 1, rows - 1)
    yy0, yy1 = y0[:, :, None], y1[:, :, None]
    xx0, xx1 = x0[:, None, :], x1[:, None, :]
    wy, wx = fy[:, :, None], fx[:, None, :]
    out = (
        features[:, yy0, xx0] * ((1 - wy) * (1 - wx))
        + features[:, yy0, xx1] * ((1 - wy) * wx)
        + features[:, yy1, xx0] * (wy * (1 - wx))
        + features[:, yy1, xx1] * (wy * wx)
    )  # (C, R, size, size)
    return np.ascontiguousarray(out.transpose(1, 0, 2, 3), np.float32)


def mask_targets(masks: np.ndarray, xyxy: np.ndarray, size: int) -> np.ndarray:
    """Mask R-CNN's mask target of each ROI: its true mask (H, W) bool sampled bilinearly in
    the ROI at ``size`` × ``size`` bin centres, then thresholded at 0.5 (R, size, size)."""
    targets = np.empty((len(xyxy), size, size), np.float32)
    for index, (mask, box) in enumerate(zip(masks, xyxy, strict=True)):
        plane = mask.astype(np.float32)[None]
        targets[index] = roi_align(plane, box[None], 1, size)[0, 0] >= 0.5
    return targets


def paste_mask(probability: np.ndarray, box: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """A ``size`` × ``size`` mask probability pasted into a scene of ``shape``: every pixel
    centre inside the box sampled bilinearly from it, thresholded at 0.5; (H, W) bool."""
    from scipy import ndimage as ndi

    size = probability.shape[0]
    height, width = shape
    x0, y0 = max(int(np.floor(box[0])), 0), max(int(np.floor(box[1])), 0)
    x1, y1 = min(int(np.ceil(box[2])), width), min(int(np.ceil(box[3])), height)
    out = np.zeros(shape, bool)
    if x1 <= x0 or y1 <= y0:
        return out
    u = ((np.arange(x0, x1) + 0.5) - box[0]) / (box[2] - box[0]) * size - 0.5
    v = ((np.arange(y0, y1) + 0.5) - box[1]) / (box[3] - box[1]) * size - 0.5
    grid = np.meshgrid(v, u, indexing="ij")
    out[y0:y1, x0:x1] = ndi.map_coordinates(probability, grid, order=1, mode="nearest") >= 0.5
    return out


def train_mask_network(
    network: Architecture, inputs: np.ndarray, targets: np.ndarray, channel: np.ndarray, *,
    epochs: int, batch_size: int, learning_rate: float, momentum: float, weight_decay: float,
    seed: int,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    r"""SGD with momentum on the mean per-pixel binary cross-entropy of each ROI's mask
    logits :math:`z` in its own class's channel against its target :math:`m`:

    .. math:: L = -\frac{1}{N m^2}\sum \big(m \log\sigma(z) + (1 - m)\log(1 - \sigma(z))\big)

    (the other classes' channels get no gradient). Weights (float64) and the mean loss of
    each epoch; ValueError naming the learning rate when the loss is not finite."""
    from ..cnn import initial_weights

    rng = np.random.default_rng(seed)
    weights = initial_weights(network, seed).astype(np.float32)
    velocity = np.zeros_like(weights)
    history = []
    for epoch in range(epochs):
        losses = []
        order = rng.permutation(len(inputs))
        for start in range(0, len(inputs), batch_size):
            batch = order[start : start + batch_size]
            logits, saved = network.forward(weights, inputs[batch], keep=True)
            z = logits[np.arange(len(batch)), channel[batch]]
            m = targets[batch]
            count = z.size
            loss = float(np.sum(np.logaddexp(0, z) - m * z)) / count
            if not np.isfinite(loss):
                raise ValueError(
                    f"detection.train_mask_head: the loss diverged at epoch {epoch + 1} with "
                    f"learning_rate={learning_rate:g}; lower the learning rate"
                )
            grad = np.zeros_like(logits)
            grad[np.arange(len(batch)), channel[batch]] = (1 / (1 + np.exp(-z)) - m) / count
            gradient = network.backward(weights, grad, saved)
            velocity *= momentum
            velocity -= learning_rate * (gradient + weight_decay * weights)
            weights += velocity
            losses.append(loss * len(batch))
        history.append(sum(losses) / len(inputs))
    return weights.astype(np.float64), np.array(history)


@dataclass(frozen=True, eq=False)
class MaskHeadModel:
    """A trained mask branch: its layers (JSON ``{"input": [C, m, m], "layers": [...]}``,
    the last giving one channel per class), weights, the classes (int64, the Faster
    R-CNN's), and the mean loss of each epoch."""

    architecture: str
    weights: np.ndarray
    classes: np.ndarray
    history: np.ndarray

    def parsed(self) -> Architecture:
        """The architecture, chained."""
        spec = json.loads(self.architecture)
        return build_architecture(tuple(spec["input"]), spec["layers"])


class MaskHeadPort(RecordPort):
    """A :class:`MaskHeadModel` whose weights fit its layers and whose output has one
    ``m`` × ``m`` map per class."""

    value_class = MaskHeadModel

    @classmethod
    def validate(cls, value: Any) -> MaskHeadModel:
        value = super().validate(value)
        for name in ("weights", "history"):
            array = getattr(value, name)
            if not isinstance(array, np.ndarray) or array.dtype != np.float64:
                raise PortValueError(f"MaskHead '{name}' must be float64")
            if not np.isfinite(array).all():
                raise PortValueError(f"MaskHead '{name}' must be finite")
        if not isinstance(value.classes, np.ndarray) or value.classes.dtype != np.int64:
            raise PortValueError("MaskHead 'classes' must be an int64 vector")
        try:
            architecture = value.parsed()
        except (ValueError, KeyError, TypeError) as error:
            raise PortValueError(f"MaskHead layers are invalid: {error}") from None
        if architecture.size != len(value.weights):
            raise PortValueError("MaskHead weights do not match its layers")
        side = architecture.shapes[0][1]
        if architecture.shapes[-1] != (len(value.classes), side, side):
            raise PortValueError(
                f"MaskHead gives {architecture.shapes[-1]} for {len(value.classes)} classes "
                f"of {side}×{side} masks"
            )
        return value

    @classmethod
    def summary(cls, value: MaskHeadModel) -> str:
        side = json.loads(value.architecture)["input"][1]
        return f"MaskHead {side}×{side} masks of classes {value.classes.tolist()}"


MaskHead = Annotated[MaskHeadModel, MaskHeadPort]
