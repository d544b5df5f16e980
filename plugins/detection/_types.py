"""The detection family's values: boxes of many scenes, and a trained detector.

::

    Detections  xyxy (M, 4) float64, score (M,), label (M,) int64 (-1: a proposal with
                no class), owner (M,) int64 scene index, scenes (how many)
    Detector    the backbone's feature layers (JSON) and their weights, the stride and
                ROI-pool size, the head network (JSON) and its weights, the object
                classes, and one ridge box regressor per class (K, D + 1, 4)

Both are frozen dataclasses of arrays and JSON scalars: validated, cached and sent to
workers in the array encoding; nothing is pickled.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np

from graphvision import PortValueError, RecordPort

from ..cnn import build_architecture
from ..shared.boxes import check_boxes

__all__ = [
    "DetectionSet",
    "Detections",
    "DetectionsPort",
    "Detector",
    "DetectorModel",
    "DetectorPort",
]


def _typed(owner: str, name: str, value: Any, dtype: type, shape: tuple) -> None:
    if (
        not isinstance(value, np.ndarray)
        or value.dtype != dtype
        or value.ndim != len(shape)
        or any(want not in (-1, got) for want, got in zip(shape, value.shape, strict=True))
    ):
        got = f"{value.dtype} {value.shape}" if isinstance(value, np.ndarray) else type(value)
        raise PortValueError(f"{owner} '{name}' must be {np.dtype(dtype).name} {shape}, got {got}")


@dataclass(frozen=True, eq=False)
class DetectionSet:
    """Boxes over ``scenes`` scenes (proposals or detections; see the module)."""

    xyxy: np.ndarray
    score: np.ndarray
    label: np.ndarray
    owner: np.ndarray
    scenes: int

    def __len__(self) -> int:
        return len(self.xyxy)

    def take(self, index: np.ndarray) -> DetectionSet:
        """The boxes at ``index`` (a mask or integer indices)."""
        return DetectionSet(
            self.xyxy[index], self.score[index], self.label[index], self.owner[index], self.scenes
        )


class DetectionsPort(RecordPort):
    """A :class:`DetectionSet`: finite boxes with x0 < x1 and y0 < y1, scores not NaN,
    owners in [0, scenes)."""

    value_class = DetectionSet

    @classmethod
    def validate(cls, value: Any) -> DetectionSet:
        value = super().validate(value)
        count = len(value.xyxy) if isinstance(value.xyxy, np.ndarray) else -1
        _typed("Detections", "xyxy", value.xyxy, np.float64, (count, 4))
        _typed("Detections", "score", value.score, np.float64, (count,))
        _typed("Detections", "label", value.label, np.int64, (count,))
        _typed("Detections", "owner", value.owner, np.int64, (count,))
        try:
            check_boxes(value.xyxy, "Detections box")
        except ValueError as error:
            raise PortValueError(str(error)) from None
        if np.isnan(value.score).any():
            raise PortValueError("Detections scores must not be NaN")
        if count and (value.owner.min() < 0 or value.owner.max() >= value.scenes):
            raise PortValueError(f"Detections 'owner' must index the {value.scenes} scenes")
        return value

    @classmethod
    def summary(cls, value: DetectionSet) -> str:
        return f"Detections {len(value)} over {value.scenes} scenes"


Detections = Annotated[DetectionSet, DetectionsPort]


@dataclass(frozen=True, eq=False)
class DetectorModel:
    """A trained Fast R-CNN style detector (see the module)."""

    feature_layers: str
    feature_weights: np.ndarray
    stride: int
    pool: int
    head_architecture: str
    head_weights: np.ndarray
    classes: np.ndarray
    regression: np.ndarray
    history: np.ndarray


class DetectorPort(RecordPort):
    """A :class:`DetectorModel` whose parts fit together: the head takes the pooled feature
    map and gives one score per class plus background; one regressor per class."""

    value_class = DetectorModel

    @classmethod
    def validate(cls, value: Any) -> DetectorModel:
        value = super().validate(value)
        for name in ("feature_weights", "head_weights", "regression", "history"):
            array = getattr(value, name)
            if not isinstance(array, np.ndarray) or array.dtype != np.float64:
                raise PortValueError(f"Detector '{name}' must be float64")
            if not np.isfinite(array).all():
                raise PortValueError(f"Detector '{name}' must be finite")
        classes_ok = isinstance(value.classes, np.ndarray) and value.classes.dtype == np.int64
        if not classes_ok or value.classes.ndim != 1:
            raise PortValueError("Detector 'classes' must be an int64 vector")
        if not isinstance(value.stride, int) or not isinstance(value.pool, int):
            raise PortValueError("Detector 'stride' and 'pool' must be integers")
        if value.stride < 1 or value.pool < 1:
            raise PortValueError("Detector 'stride' and 'pool' must be at least 1")
        try:
            layers = json.loads(value.feature_layers)
            side = 16 * value.pool * value.stride  # any map large enough to chain
            features = build_architecture((1, side, side), layers)
            spec = json.loads(value.head_architecture)
            head = build_architecture(tuple(spec["input"]), spec["layers"])
        except (ValueError, KeyError, TypeError) as error:
            raise PortValueError(f"Detector layers are invalid: {error}") from None
        if features.size != len(value.feature_weights) or head.size != len(value.head_weights):
            raise PortValueError("Detector weights do not match its layers")
        classes = len(value.classes)
        pooled = int(np.prod(head.shapes[0]))
        if head.shapes[-1] != (classes + 1,) or value.regression.shape != (classes, pooled + 1, 4):
            raise PortValueError(
                f"Detector head gives {head.shapes[-1]} scores and {value.regression.shape} "
                f"regressors for {classes} classes plus background"
            )
        return value

    @classmethod
    def summary(cls, value: DetectorModel) -> str:
        return f"Detector of classes {value.classes.tolist()}"


Detector = Annotated[DetectorModel, DetectorPort]
