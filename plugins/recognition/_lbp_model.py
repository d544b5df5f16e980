"""A trained cascade of multi-block LBP stumps as a value (:class:`LBPCascadeModel`, named
arrays plus a JSON header) and its port; see :mod:`._lbp_cascade` for how a window is
classified."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np

from graphvision import PortValueError, RecordPort

__all__ = [
    "LBPCascade",
    "LBPCascadeModel",
    "LBPCascadePort",
]


@dataclass(frozen=True, eq=False)
class LBPCascadeModel:
    """A boosted cascade of MB-LBP stumps (see the module).

    ``rects`` (F, 4) int64: each feature's (x, y, block width, block height) in the
    window; ``feature`` (K,) int64: the feature of each weak classifier; ``subsets``
    (K, 8) uint32: the 256-bit set of codes that choose ``leaves[k, 0]`` over
    ``leaves[k, 1]``; ``leaves`` (K, 2) float64; ``stage`` (K,) int64: the stage of each
    weak classifier, non-decreasing from 0; ``stage_threshold`` (S,) float64;
    ``height``, ``width``: the window; ``source``: where it was read from.
    """

    rects: np.ndarray
    feature: np.ndarray
    subsets: np.ndarray
    leaves: np.ndarray
    stage: np.ndarray
    stage_threshold: np.ndarray
    height: int = 24
    width: int = 24
    source: str = ""

    @property
    def stage_end(self) -> np.ndarray:
        """One past the last weak classifier of each stage, int64 (S,)."""
        counts = np.bincount(self.stage, minlength=len(self.stage_threshold))
        return np.cumsum(counts).astype(np.int64)


def _typed(name: str, value: Any, dtype: type, ndim: int) -> np.ndarray:
    if not isinstance(value, np.ndarray) or value.dtype != dtype or value.ndim != ndim:
        got = f"{value.dtype} {value.shape}" if isinstance(value, np.ndarray) else type(value)
        raise PortValueError(
            f"LBPCascade '{name}' must be a {ndim}-D {np.dtype(dtype).name}, got {got}"
        )
    return value


class LBPCascadePort(RecordPort):
    """An :class:`LBPCascadeModel` whose parts fit together: every feature's 3 × 3 blocks
    inside the window, feature indices in range, stages numbered 0 … S − 1 in order with
    at least one weak classifier each, finite leaves and thresholds."""

    value_class = LBPCascadeModel

    @classmethod
    def validate(cls, value: Any) -> LBPCascadeModel:
        value = super().validate(value)
        rects = _typed("rects", value.rects, np.int64, 2)
        feature = _typed("feature", value.feature, np.int64, 1)
        subsets = _typed("subsets", value.subsets, np.uint32, 2)
        leaves = _typed("leaves", value.leaves, np.float64, 2)
        stage = _typed("stage", value.stage, np.int64, 1)
        thresholds = _typed("stage_threshold", value.stage_threshold, np.float64, 1)
        if not isinstance(value.height, int) or not isinstance(value.width, int):
            raise PortValueError("LBPCascade 'height' and 'width' must be integers")
        if not 3 <= value.height <= 1024 or not 3 <= value.width <= 1024:
            raise PortValueError(
                f"LBPCascade window must be 3 to 1024 pixels a side, got "
                f"{value.height}×{value.width}"
            )
        count = len(feature)
        if rects.shape[1:] != (4,) or len(rects) == 0:
            raise PortValueError(f"LBPCascade 'rects' must be (F, 4) with F ≥ 1, got {rects.shape}")
        if subsets.shape != (count, 8) or leaves.shape != (count, 2) or stage.shape != (count,):
            raise PortValueError(
                f"LBPCascade needs subsets (K, 8), leaves (K, 2) and stage (K,) for its K = "
                f"{count} weak classifiers, got {subsets.shape}, {leaves.shape}, {stage.shape}"
            )
        if count == 0 or len(thresholds) == 0:
            raise PortValueError("LBPCascade needs at least one stage and one weak classifier")
        if not (np.isfinite(leaves).all() and np.isfinite(thresholds).all()):
            raise PortValueError("LBPCascade leaves and stage thresholds must be finite")
        if feature.min() < 0 or feature.max() >= len(rects):
            raise PortValueError(f"LBPCascade 'feature' must index the {len(rects)} features")
        x, y, w, h = rects.T
        outside = (x < 0) | (y < 0) | (w < 1) | (h < 1)
        outside |= (x + 3 * w > value.width) | (y + 3 * h > value.height)
        if outside.any():
            row = int(np.flatnonzero(outside)[0])
            raise PortValueError(
                f"LBPCascade feature {row} (x, y, w, h) = {rects[row].tolist()}: its 3 × 3 "
                f"blocks must lie inside the {value.width}×{value.height} window"
            )
        stages = len(thresholds)
        if (np.diff(stage) < 0).any() or stage[0] != 0 or stage[-1] != stages - 1:
            raise PortValueError(
                f"LBPCascade 'stage' must number the weak classifiers' stages 0 … {stages - 1} "
                "in order"
            )
        if (np.bincount(stage, minlength=stages) == 0).any():
            raise PortValueError("LBPCascade has a stage without a weak classifier")
        return value

    @classmethod
    def preview(cls, value: LBPCascadeModel) -> np.ndarray | None:
        """Where the cascade looks: how many weak classifiers cover each window pixel,
        earlier stages counting more (a stage-s classifier weighs 1 / (s + 1)),
        stretched to [0, 1] and enlarged 8 times."""
        return feature_map(value)

    @classmethod
    def summary(cls, value: LBPCascadeModel) -> str:
        return (
            f"LBPCascade {len(value.stage_threshold)} stages, {len(value.feature)} weak "
            f"classifiers, {value.width}×{value.height} window"
        )


LBPCascade = Annotated[LBPCascadeModel, LBPCascadePort]


def feature_map(model: LBPCascadeModel, zoom: int = 8) -> np.ndarray:
    """The cascade's attention over its window (see :meth:`LBPCascadePort.preview`)."""
    weight = np.zeros((model.height, model.width))
    for k, index in enumerate(model.feature):
        x, y, w, h = (int(v) for v in model.rects[index])
        weight[y : y + 3 * h, x : x + 3 * w] += 1.0 / (model.stage[k] + 1)
    weight /= max(float(weight.max()), 1e-12)
    return np.kron(weight, np.ones((zoom, zoom))).astype(np.float32)
