"""Port types whose values are frozen dataclasses of arrays: keypoints, matches, cameras, boxes."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from graphvision.errors import PortValueError
from graphvision.values.ports import RecordPort

__all__ = [
    "BoxSet",
    "BoxesPort",
    "CameraPort",
    "KeypointSet",
    "KeypointsPort",
    "MatchSet",
    "MatchesPort",
    "PinholeCamera",
]


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
    affine: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 2)))

    def __post_init__(self) -> None:
        if len(self.affine) == 0 and len(self.xy) > 0:  # default: identity shapes
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

    @classmethod
    def preview(cls, value: KeypointSet) -> np.ndarray | None:
        from graphvision.values.pictures import scatter

        return scatter(value.xy)


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


@dataclass(frozen=True, eq=False)
class PinholeCamera:
    r"""A calibrated pinhole camera with lens distortion.

    ``K`` is the 3×3 calibration matrix, ``R`` the 3×3 rotation from world to
    camera coordinates and ``C`` the camera centre in world coordinates, so
    that a world point :math:`\tilde X` projects as

    .. math:: x \sim P X, \qquad P = K [R \mid -R \tilde C]

    (the seed's "Camera geometry"). ``distortion`` holds the radial and
    tangential coefficients in OpenCV's order ``(k1, k2, p1, p2, k3)``,
    applied to normalised coordinates before ``K``. ``size`` is the image
    ``(width, height)`` in pixels.
    """

    K: np.ndarray
    R: np.ndarray = field(default_factory=lambda: np.eye(3))
    C: np.ndarray = field(default_factory=lambda: np.zeros(3))
    distortion: np.ndarray = field(default_factory=lambda: np.zeros(5))
    size: np.ndarray = field(default_factory=lambda: np.zeros(2, np.int64))

    @property
    def t(self) -> np.ndarray:
        """The translation :math:`t = -R \tilde C` of :math:`[R \\mid t]`."""
        return -self.R @ self.C

    @property
    def P(self) -> np.ndarray:
        """The 3×4 projection matrix :math:`K [R \\mid -R \tilde C]`."""
        return self.K @ np.hstack([self.R, self.t[:, None]])


class CameraPort(RecordPort):
    """A :class:`PinholeCamera`: finite float64 K (upper triangular, K[2, 2] = 1), R a
    rotation, C (3,), distortion (5,), size (2,) int64.

    Degrees of freedom: P = K[R | −RC̃] has 11 (a 3×4 matrix up to scale): 5 in K
    (fx, fy, skew, cx, cy), 3 in R, 3 in C̃; the lens adds 5 (k1, k2, p1, p2, k3)."""

    value_class = PinholeCamera

    @classmethod
    def validate(cls, value: Any) -> PinholeCamera:
        value = super().validate(value)
        for name, shape in (("K", (3, 3)), ("R", (3, 3)), ("C", (3,)), ("distortion", (5,))):
            item = getattr(value, name)
            if not isinstance(item, np.ndarray) or item.dtype != np.float64 or item.shape != shape:
                got = f"{item.dtype} {item.shape}" if isinstance(item, np.ndarray) else type(item)
                raise PortValueError(f"camera '{name}' must be float64 {shape}, got {got}")
            if not np.isfinite(item).all():
                raise PortValueError(f"camera '{name}' must be finite")
        _column("size", value.size, 2, np.int64)
        K, R = value.K, value.R
        if K[2, 2] != 1.0 or K[1, 0] != 0.0 or K[2, 0] != 0.0 or K[2, 1] != 0.0:
            raise PortValueError(f"camera K must be upper triangular with K[2, 2] = 1, got {K}")
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise PortValueError("camera R must be a rotation (R Rᵀ = I, det R = +1)")
        return value

    @classmethod
    def summary(cls, value: PinholeCamera) -> str:
        return f"Camera f=({value.K[0, 0]:.4g}, {value.K[1, 1]:.4g})"


@dataclass(frozen=True, eq=False)
class BoxSet:
    """N axis-aligned boxes ``xyxy[k] = (x0, y0, x1, y1)`` (pixels, x0 < x1, y0 < y1)
    with a detection ``score[k]`` each (larger is more confident)."""

    xyxy: np.ndarray
    score: np.ndarray

    def __len__(self) -> int:
        return len(self.xyxy)

    def take(self, index: np.ndarray) -> BoxSet:
        """The boxes at ``index`` (a boolean mask or integer indices)."""
        return BoxSet(self.xyxy[index], self.score[index])


class BoxesPort(RecordPort):
    """A :class:`BoxSet`: ``xyxy`` float64 (N, 4) finite with x0 < x1 and y0 < y1, ``score``
    float64 (N,) not NaN (± inf allowed: "always keep" or "never"); N may be 0."""

    value_class = BoxSet

    @classmethod
    def validate(cls, value: Any) -> BoxSet:
        value = super().validate(value)
        count = len(value.xyxy) if isinstance(value.xyxy, np.ndarray) else -1
        _column("xyxy", value.xyxy, count, np.float64, (4,))
        _column("score", value.score, count, np.float64)
        xyxy = value.xyxy
        if not np.isfinite(xyxy).all() or (xyxy[:, 2:] <= xyxy[:, :2]).any():
            raise PortValueError("boxes must be finite (x0, y0, x1, y1) with x0 < x1 and y0 < y1")
        if np.isnan(value.score).any():
            row = int(np.flatnonzero(np.isnan(value.score))[0])
            raise PortValueError(f"box {row} has a NaN score: scores order boxes, NaN cannot")
        return value

    @classmethod
    def summary(cls, value: BoxSet) -> str:
        return f"Boxes {len(value)}"
