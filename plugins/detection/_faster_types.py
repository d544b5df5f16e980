"""The ``FasterRcnn`` port type: a trained Faster R-CNN (Ren et al. 2015).

::

    feature_layers   JSON list of the backbone's feature layers (convolution, ReLU,
                     pooling); the first ``frozen`` of them kept from the backbone, the
                     rest fine-tuned; ``feature_weights`` float64, ``stride`` pixels per cell
    anchors          JSON {"sizes": [...], "ratios": [...]} (A = sizes × ratios shapes)
    rpn_layers       JSON list of the RPN's layers on the feature map (last: 5A outputs per
                     cell: A objectness logits, then 4 codings per shape); ``rpn_weights``
    head             JSON {"input": [C, pool, pool], "layers": [...]}, last layer 5K + 1
                     outputs (K + 1 class scores, then 4 codings per class); ``head_weights``
    classes          int64 (K,); ``history`` the mean joint loss of each epoch
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np

from graphvision import PortValueError, RecordPort

from ..cnn import Architecture, build_architecture

__all__ = ["FasterRcnn", "FasterRcnnModel", "FasterRcnnPort"]


@dataclass(frozen=True, eq=False)
class FasterRcnnModel:
    """A trained Faster R-CNN (see the module)."""

    feature_layers: str
    feature_weights: np.ndarray
    frozen: int
    stride: int
    pool: int
    anchors: str
    rpn_layers: str
    rpn_weights: np.ndarray
    head: str
    head_weights: np.ndarray
    classes: np.ndarray
    history: np.ndarray

    def shapes(self) -> dict[str, list[float]]:
        """The anchor sizes and ratios."""
        return dict(json.loads(self.anchors))

    def architectures(self, image_shape: tuple[int, int]) -> tuple[Architecture, ...]:
        """The feature layers on a gray image of ``image_shape``, the RPN on their map, and
        the head."""
        features = build_architecture((1, *image_shape), json.loads(self.feature_layers))
        rpn = build_architecture(features.shapes[-1], json.loads(self.rpn_layers))
        spec = json.loads(self.head)
        return features, rpn, build_architecture(tuple(spec["input"]), spec["layers"])


class FasterRcnnPort(RecordPort):
    """A :class:`FasterRcnnModel` whose parts fit: finite float64 weights of the right
    sizes, 5A RPN outputs for A anchor shapes, 5K + 1 head outputs for K classes."""

    value_class = FasterRcnnModel

    @classmethod
    def validate(cls, value: Any) -> FasterRcnnModel:
        value = super().validate(value)
        for name in ("feature_weights", "rpn_weights", "head_weights", "history"):
            array = getattr(value, name)
            if not isinstance(array, np.ndarray) or array.dtype != np.float64:
                raise PortValueError(f"FasterRcnn '{name}' must be float64")
            if not np.isfinite(array).all():
                raise PortValueError(f"FasterRcnn '{name}' must be finite")
        if not isinstance(value.classes, np.ndarray) or value.classes.dtype != np.int64:
            raise PortValueError("FasterRcnn 'classes' must be an int64 vector")
        try:
            side = 16 * value.stride * value.pool
            features, rpn, head = value.architectures((side, side))
            shapes = value.shapes()
        except (ValueError, KeyError, TypeError) as error:
            raise PortValueError(f"FasterRcnn layers are invalid: {error}") from None
        sizes = (features.size, rpn.size, head.size)
        given = (len(value.feature_weights), len(value.rpn_weights), len(value.head_weights))
        if sizes != given:
            raise PortValueError(f"FasterRcnn weights {given} do not match its layers {sizes}")
        count = len(shapes["sizes"]) * len(shapes["ratios"])
        if rpn.shapes[-1][0] != 5 * count or head.shapes[-1] != (5 * len(value.classes) + 1,):
            raise PortValueError(
                f"FasterRcnn gives {rpn.shapes[-1][0]} RPN outputs for {count} anchor shapes "
                f"and {head.shapes[-1]} head outputs for {len(value.classes)} classes"
            )
        return value

    @classmethod
    def summary(cls, value: FasterRcnnModel) -> str:
        return f"FasterRcnn of classes {value.classes.tolist()}"


FasterRcnn = Annotated[FasterRcnnModel, FasterRcnnPort]
