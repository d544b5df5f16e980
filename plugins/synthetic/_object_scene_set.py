"""The value of object scenes (:class:`ObjectSceneSet`: scenes and the true instances of a
model in them) and its port; see :mod:`._object_scenes` for how they are made."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np

from graphvision import PortValueError, RecordPort

__all__ = [
    "ObjectSceneSet",
    "ObjectScenes",
    "ObjectScenesPort",
    "model_corners",
]


def model_corners(width: int, height: int) -> np.ndarray:
    """The model's corner pixel centres (0, 0), (w-1, 0), (w-1, h-1), (0, h-1), (4, 2)."""
    return np.array([[0, 0], [width - 1, 0], [width - 1, height - 1], [0, height - 1]], float)


@dataclass(frozen=True, eq=False)
class ObjectSceneSet:
    """Scenes (N, H, W) float32 in [0, 1] and the true instances of the model in them
    (see the module): ``quads`` (M, 4, 2), ``homographies`` (M, 3, 3) model → scene,
    ``owner`` (M,) int64, ``visible``, ``tilt`` (degrees) and ``scale`` (M,) float64."""

    images: np.ndarray
    quads: np.ndarray
    homographies: np.ndarray
    owner: np.ndarray
    visible: np.ndarray
    tilt: np.ndarray
    scale: np.ndarray

    def __len__(self) -> int:
        return len(self.images)

    def quads_of(self, scene: int) -> np.ndarray:
        """The true quadrilaterals (K, 4, 2) of one scene."""
        return self.quads[self.owner == scene]


class ObjectScenesPort(RecordPort):
    """An :class:`ObjectSceneSet`: images float32 (N, H, W) in [0, 1]; quads float64
    (M, 4, 2) and homographies (M, 3, 3), finite; owner int64 (M,) in [0, N); visible,
    tilt and scale float64 (M,)."""

    value_class = ObjectSceneSet

    @classmethod
    def validate(cls, value: Any) -> ObjectSceneSet:
        value = super().validate(value)
        images = value.images
        if not isinstance(images, np.ndarray) or images.dtype != np.float32 or images.ndim != 3:
            raise PortValueError("ObjectScenes 'images' must be float32 (N, H, W)")
        count = len(value.owner) if isinstance(value.owner, np.ndarray) else -1
        shapes = {
            "quads": (np.float64, (count, 4, 2)),
            "homographies": (np.float64, (count, 3, 3)),
            "owner": (np.int64, (count,)),
            "visible": (np.float64, (count,)),
            "tilt": (np.float64, (count,)),
            "scale": (np.float64, (count,)),
        }
        for name, (dtype, shape) in shapes.items():
            column = getattr(value, name)
            if not isinstance(column, np.ndarray) or column.dtype != dtype or column.shape != shape:
                raise PortValueError(
                    f"ObjectScenes '{name}' must be {np.dtype(dtype).name} {shape}: one per "
                    "instance"
                )
        if not (np.isfinite(value.quads).all() and np.isfinite(value.homographies).all()):
            raise PortValueError("ObjectScenes 'quads' and 'homographies' must be finite")
        if count and (value.owner.min() < 0 or value.owner.max() >= len(images)):
            raise PortValueError(f"ObjectScenes 'owner' must index the {len(images)} scenes")
        return value

    @classmethod
    def preview(cls, value: ObjectSceneSet) -> np.ndarray | None:
        """The first four scenes side by side, two white columns apart."""
        shown = value.images[:4]
        height, width = shown.shape[1:]
        canvas = np.ones((height, len(shown) * (width + 2)), np.float32)
        for index, image in enumerate(shown):
            canvas[:, index * (width + 2) : index * (width + 2) + width] = image
        return canvas

    @classmethod
    def summary(cls, value: ObjectSceneSet) -> str:
        side = f"{value.images.shape[1]}×{value.images.shape[2]}"
        return f"ObjectScenes {len(value)} × {side}, {len(value.owner)} instances"


ObjectScenes = Annotated[ObjectSceneSet, ObjectScenesPort]
