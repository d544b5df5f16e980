"""The stereo family's values: disparity and depth maps with invalid pixels marked NaN."""

from __future__ import annotations

from typing import Annotated, Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from graphvision import ArrayPort, PortValueError

__all__ = [
    "Depth",
    "DepthPort",
    "Disparity",
    "DisparityPort",
    "Frames",
    "FramesPort",
    "PointColours",
    "PointColoursPort",
]


class DisparityPort(ArrayPort):
    """A disparity map: ``float32`` ``H×W``, left pixel ``(x, y)`` matches right ``(x − d, y)``.

    Pixels without an estimate are NaN (never 0, a valid disparity); no
    infinities.
    """

    ndims: ClassVar[tuple[int, ...]] = (2,)
    dtypes = (np.float32,)
    expected = "float32 H×W, NaN where invalid"
    units: ClassVar[str] = "disparity, pixels"  # shown with the map's colour bar

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if np.isinf(value).any():
            raise PortValueError(
                f"expected {cls.type_name()} with no infinities (NaN marks invalid)"
            )
        return value

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        from ._colour_map import colour_map

        return colour_map(value)


class DepthPort(DisparityPort):
    """A depth map: ``float32`` ``H×W``, distance along the optical axis (> 0), NaN if invalid."""

    expected = "float32 H×W, > 0, NaN where invalid"
    units: ClassVar[str] = "depth, in the unit of the baseline"

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        finite = value[np.isfinite(value)]
        if finite.size and float(finite.min()) <= 0.0:
            raise PortValueError(
                f"expected {cls.type_name()} > 0 (NaN where invalid), got {float(finite.min()):g}"
            )
        return value


class FramesPort(ArrayPort):
    """A stack of gray frames ``N×H×W`` ``float32`` in [0, 1] (captures of projected patterns)."""

    ndims: ClassVar[tuple[int, ...]] = (3,)
    dtypes = (np.float32,)
    expected = "float32 N×H×W in [0, 1]"

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if not (float(value.min()) >= 0.0 and float(value.max()) <= 1.0):
            raise PortValueError(f"expected {cls.type_name()} values in [0, 1]")
        return value

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        return np.concatenate(list(value[: min(len(value), 4)]), axis=1)


class PointColoursPort(ArrayPort):
    """The colour of each point of a cloud, row for row: ``float32`` ``N×3`` RGB in [0, 1]
    (N may be 0); viewers colour the cloud by it (``stereo.coloured_points``)."""

    ndims: ClassVar[tuple[int, ...]] = (2,)
    dtypes = (np.float32,)
    expected = "float32 N×3 RGB in [0, 1]"
    allow_empty = True

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape[1] != 3:
            raise PortValueError(f"expected {cls.type_name()} ({cls.expected}), got {value.shape}")
        if value.size and not (float(value.min()) >= 0.0 and float(value.max()) <= 1.0):
            raise PortValueError(f"expected {cls.type_name()} values in [0, 1]")
        return value

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        return None


Disparity = Annotated[NDArray[np.float32], DisparityPort]
Depth = Annotated[NDArray[np.float32], DepthPort]
Frames = Annotated[NDArray[np.float32], FramesPort]
PointColours = Annotated[NDArray[np.float32], PointColoursPort]
