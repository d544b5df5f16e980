"""The port type of an image pyramid: a list of levels, each smaller than the last."""

from __future__ import annotations

import dataclasses
from typing import Annotated, Any

import numpy as np

from graphvision import PortType, PortValueError

__all__ = ["ImagePyramid", "Pyramid", "PyramidPort"]


@dataclasses.dataclass(frozen=True)
class ImagePyramid:
    """Levels finest first (``levels[0]`` has the input's size) and how they were made.

    ``kind`` is ``gaussian``, ``laplacian`` (band-pass levels, the last one the
    coarsest Gaussian level) or ``naive`` (subsampled without smoothing).
    """

    levels: tuple[np.ndarray, ...]
    kind: str


class PyramidPort(PortType):
    """An :class:`ImagePyramid`: float32 levels, H×W or H×W×3, finest first."""

    @classmethod
    def validate(cls, value: Any) -> ImagePyramid:
        if not isinstance(value, ImagePyramid) or not value.levels:
            raise PortValueError(f"expected Pyramid (ImagePyramid with levels), got {value!r:.80}")
        for index, level in enumerate(value.levels):
            if not isinstance(level, np.ndarray) or level.dtype != np.float32:
                raise PortValueError(
                    f"expected Pyramid level {index} as float32, got {level!r:.60}"
                )
        return value

    @classmethod
    def encode(cls, value: ImagePyramid) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays = {f"level{index}": level for index, level in enumerate(value.levels)}
        return arrays, {"kind": value.kind, "count": len(value.levels)}

    @classmethod
    def decode(cls, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> ImagePyramid:
        levels = tuple(arrays[f"level{index}"] for index in range(meta["count"]))
        return ImagePyramid(levels, meta["kind"])

    @classmethod
    def summary(cls, value: ImagePyramid) -> str:
        sizes = ", ".join("×".join(map(str, level.shape[:2])) for level in value.levels)
        return f"{value.kind} pyramid ({sizes})"


Pyramid = Annotated[ImagePyramid, PyramidPort]
