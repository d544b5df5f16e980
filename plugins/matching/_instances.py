"""The record of found instances of a model (:class:`InstanceSet`) and its port."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np

from graphvision import PortValueError, RecordPort

__all__ = [
    "InstanceSet",
    "Instances",
    "InstancesPort",
]


@dataclass(frozen=True, eq=False)
class InstanceSet:
    """K found instances of a model: ``quads`` (K, 4, 2) the model's corners in the scene,
    ``homographies`` (K, 3, 3) model → scene, ``inliers`` (K,) int64 the matches that
    support each, ``probability`` (K,) Lowe's :math:`P(m \\mid f)`, ``owner`` (K,) int64
    the scene each was found in, out of ``scenes`` scenes."""

    quads: np.ndarray
    homographies: np.ndarray
    inliers: np.ndarray
    probability: np.ndarray
    owner: np.ndarray
    scenes: int = 1

    def __len__(self) -> int:
        return len(self.quads)

    @classmethod
    def empty(cls, scenes: int = 1) -> InstanceSet:
        return cls(
            np.zeros((0, 4, 2)),
            np.zeros((0, 3, 3)),
            np.zeros(0, np.int64),
            np.zeros(0),
            np.zeros(0, np.int64),
            scenes,
        )

    @classmethod
    def concatenate(cls, parts: list[InstanceSet], scenes: int) -> InstanceSet:
        """One set from per-scene sets (their ``owner`` already set)."""
        if not parts:
            return cls.empty(scenes)
        return cls(
            np.concatenate([p.quads for p in parts]).reshape(-1, 4, 2),
            np.concatenate([p.homographies for p in parts]).reshape(-1, 3, 3),
            np.concatenate([p.inliers for p in parts]).astype(np.int64),
            np.concatenate([p.probability for p in parts]).astype(np.float64),
            np.concatenate([p.owner for p in parts]).astype(np.int64),
            scenes,
        )


class InstancesPort(RecordPort):
    """An :class:`InstanceSet`: quads float64 (K, 4, 2), homographies float64 (K, 3, 3),
    finite; inliers and owner int64 (K,), owner in [0, scenes); probability float64 (K,)."""

    value_class = InstanceSet

    @classmethod
    def validate(cls, value: Any) -> InstanceSet:
        value = super().validate(value)
        count = len(value.quads) if isinstance(value.quads, np.ndarray) else -1
        shapes = {
            "quads": (np.float64, (count, 4, 2)),
            "homographies": (np.float64, (count, 3, 3)),
            "inliers": (np.int64, (count,)),
            "probability": (np.float64, (count,)),
            "owner": (np.int64, (count,)),
        }
        for name, (dtype, shape) in shapes.items():
            column = getattr(value, name)
            if not isinstance(column, np.ndarray) or column.dtype != dtype or column.shape != shape:
                raise PortValueError(
                    f"Instances '{name}' must be {np.dtype(dtype).name} {shape}: one per instance"
                )
        if not (np.isfinite(value.quads).all() and np.isfinite(value.homographies).all()):
            raise PortValueError("Instances 'quads' and 'homographies' must be finite")
        if not isinstance(value.scenes, int) or value.scenes < 1:
            raise PortValueError(f"Instances 'scenes' must be a positive int, got {value.scenes!r}")
        if count > 0 and (value.owner.min() < 0 or value.owner.max() >= value.scenes):
            raise PortValueError(f"Instances 'owner' must index the {value.scenes} scenes")
        return value

    @classmethod
    def summary(cls, value: InstanceSet) -> str:
        return f"Instances {len(value)} in {value.scenes} scene(s)"


Instances = Annotated[InstanceSet, InstancesPort]
