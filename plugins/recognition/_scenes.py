"""Values of face detection over several scenes: the scenes (a stack of gray images) and the
boxes found in each (:class:`SceneBoxSet`), with their ports."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np
from numpy.typing import NDArray

from graphvision import ArrayPort, PortValueError, RecordPort

from ..shared.boxes import check_boxes

__all__ = [
    "SceneBoxSet",
    "SceneBoxes",
    "SceneBoxesPort",
    "SceneImages",
    "SceneImagesPort",
]


class SceneImagesPort(ArrayPort):
    """N equally sized gray scenes: ``float32`` ``N×H×W`` in [0, 1], N ≥ 1."""

    ndims = (3,)
    dtypes = (np.float32,)
    expected = "float32 N×H×W in [0, 1]"

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if len(value) == 0 or not (float(value.min()) >= 0.0 and float(value.max()) <= 1.0):
            raise PortValueError("expected SceneImages: at least one scene, values in [0, 1]")
        return value

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        """The first four scenes side by side."""
        return np.concatenate(list(value[:4]), axis=1)


SceneImages = Annotated[NDArray[np.float32], SceneImagesPort]


@dataclass(frozen=True, eq=False)
class SceneBoxSet:
    """Boxes in ``scenes`` scenes (found by a detector, or the true faces): box k lies in
    scene ``owner[k]``."""

    xyxy: np.ndarray
    score: np.ndarray
    owner: np.ndarray
    scenes: int

    def __len__(self) -> int:
        return len(self.xyxy)

    def boxes_of(self, scene: int) -> tuple[np.ndarray, np.ndarray]:
        """The boxes and scores found in one scene."""
        mine = self.owner == scene
        return self.xyxy[mine], self.score[mine]


class SceneBoxesPort(RecordPort):
    """A :class:`SceneBoxSet`: xyxy float64 (M, 4) with x0 < x1 and y0 < y1, score float64
    (M,) not NaN, owner int64 (M,) in [0, scenes)."""

    value_class = SceneBoxSet

    @classmethod
    def validate(cls, value: Any) -> SceneBoxSet:
        value = super().validate(value)
        columns = {"xyxy": (value.xyxy, 2), "score": (value.score, 1), "owner": (value.owner, 1)}
        for name, (column, ndim) in columns.items():
            dtype = np.int64 if name == "owner" else np.float64
            if not isinstance(column, np.ndarray) or column.dtype != dtype or column.ndim != ndim:
                raise PortValueError(f"SceneBoxes '{name}' must be {np.dtype(dtype).name} {ndim}-D")
        count = len(value.xyxy)
        if value.xyxy.shape[1:] != (4,) or len(value.score) != count or len(value.owner) != count:
            raise PortValueError("SceneBoxes needs xyxy (M, 4), score (M,) and owner (M,)")
        try:
            check_boxes(value.xyxy, "SceneBoxes box")
        except ValueError as error:
            raise PortValueError(str(error)) from None
        if np.isnan(value.score).any():
            raise PortValueError("SceneBoxes scores must not be NaN")
        if not isinstance(value.scenes, int) or value.scenes < 0:
            raise PortValueError("SceneBoxes 'scenes' must be a count")
        if count and (value.owner.min() < 0 or value.owner.max() >= value.scenes):
            raise PortValueError(f"SceneBoxes 'owner' must index the {value.scenes} scenes")
        return value

    @classmethod
    def summary(cls, value: SceneBoxSet) -> str:
        return f"SceneBoxes {len(value)} in {value.scenes} scenes"


SceneBoxes = Annotated[SceneBoxSet, SceneBoxesPort]
