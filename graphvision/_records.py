"""Port types whose values are small frozen dataclasses of arrays: keypoints and matches."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._errors import PortValueError
from ._ports import RecordPort

__all__ = ["KeypointSet", "KeypointsPort", "MatchSet", "MatchesPort"]


def _column(name: str, value: Any, count: int, dtype: type, shape: tuple = ()) -> None:
    if not isinstance(value, np.ndarray) or value.dtype != dtype or value.shape != (count, *shape):
        got = f"{value.dtype} {value.shape}" if isinstance(value, np.ndarray) else type(value)
        raise PortValueError(
            f"'{name}' must be {np.dtype(dtype).name} {(count, *shape)}, got {got}"
        )


@dataclass(frozen=True, eq=False)
class KeypointSet:
    """N keypoints: position ``xy`` (x = column, y = row), ``scale`` (σ in pixels),
    ``orientation`` (radians, from +x towards +y), ``response`` (detector strength),
    and ``affine`` (2×2 shape of the normalised region; identity when not adapted).
    """

    xy: np.ndarray
    scale: np.ndarray
    orientation: np.ndarray
    response: np.ndarray
    affine: np.ndarray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        if self.affine is None:
            count = len(self.xy)
            object.__setattr__(self, "affine", np.tile(np.eye(2), (count, 1, 1)))

    def __len__(self) -> int:
        return len(self.xy)

    @classmethod
    def empty(cls) -> KeypointSet:
        zero = np.zeros(0)
        return cls(np.zeros((0, 2)), zero, zero.copy(), zero.copy())

    def take(self, index: np.ndarray) -> KeypointSet:
        """The keypoints at ``index`` (a boolean mask or integer indices)."""
        return KeypointSet(
            self.xy[index],
            self.scale[index],
            self.orientation[index],
            self.response[index],
            self.affine[index],
        )


class KeypointsPort(RecordPort):
    """A :class:`KeypointSet`."""

    value_class = KeypointSet

    @classmethod
    def validate(cls, value: Any) -> KeypointSet:
        value = super().validate(value)
        count = len(value.xy) if isinstance(value.xy, np.ndarray) else -1
        _column("xy", value.xy, count, np.float64, (2,))
        for name in ("scale", "orientation", "response"):
            _column(name, getattr(value, name), count, np.float64)
        _column("affine", value.affine, count, np.float64, (2, 2))
        if not np.isfinite(value.xy).all():
            raise PortValueError("keypoint positions must be finite")
        return value

    @classmethod
    def summary(cls, value: KeypointSet) -> str:
        return f"Keypoints {len(value)}"


@dataclass(frozen=True, eq=False)
class MatchSet:
    """M matches: ``pairs[k] = (i, j)`` pairs keypoint ``i`` of the first set with ``j``
    of the second; ``distance[k]`` is their descriptor distance."""

    pairs: np.ndarray
    distance: np.ndarray

    def __len__(self) -> int:
        return len(self.pairs)

    def take(self, index: np.ndarray) -> MatchSet:
        return MatchSet(self.pairs[index], self.distance[index])


class MatchesPort(RecordPort):
    """A :class:`MatchSet`."""

    value_class = MatchSet

    @classmethod
    def validate(cls, value: Any) -> MatchSet:
        value = super().validate(value)
        count = len(value.pairs) if isinstance(value.pairs, np.ndarray) else -1
        _column("pairs", value.pairs, count, np.int64, (2,))
        _column("distance", value.distance, count, np.float64)
        return value

    @classmethod
    def summary(cls, value: MatchSet) -> str:
        return f"Matches {len(value)}"
