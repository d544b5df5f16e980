"""Geometric port types: 2-D and 3-D points, descriptors, homographies."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from graphvision.errors import PortValueError
from graphvision.values.ports import ArrayPort, _fail

__all__ = [
    "DescriptorsPort",
    "HomographyPort",
    "Points2DPort",
    "Points3DPort",
]


class Points2DPort(ArrayPort):
    """Points ``(x, y)`` = (column, row): ``float64`` ``N×2`` (N may be 0), finite."""

    ndims = (2,)
    dtypes = (np.float64,)
    expected = "float64 N×2 (x, y)"
    allow_empty = True

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape[1] != 2:
            raise _fail(cls, cls.expected, value)
        if not np.isfinite(value).all():
            raise PortValueError("expected Points2D with finite coordinates, got NaN or inf")
        return value

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        from graphvision.values.pictures import scatter

        return scatter(value)


class DescriptorsPort(ArrayPort):
    """Feature descriptors: ``float32`` ``N×D``, one row per keypoint (N may be 0)."""

    ndims = (2,)
    dtypes = (np.float32,)
    expected = "float32 N×D"
    allow_empty = True


class Points3DPort(ArrayPort):
    """3-D points ``(X, Y, Z)``: ``float64`` ``N×3`` (N may be 0), finite; written as PLY."""

    ndims = (2,)
    dtypes = (np.float64,)
    expected = "float64 N×3 (X, Y, Z)"
    allow_empty = True

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape[1] != 3:
            raise _fail(cls, cls.expected, value)
        if not np.isfinite(value).all():
            raise PortValueError("expected Points3D with finite coordinates, got NaN or inf")
        return value

    @classmethod
    def write(cls, value: np.ndarray, stem: Path) -> list[Path]:
        """A binary little-endian PLY file of ``double`` x, y, z vertices (MeshLab,
        CloudCompare, Open3D and Blender read it)."""
        path = stem.with_suffix(".ply")
        header = (
            f"ply\nformat binary_little_endian 1.0\nelement vertex {len(value)}\n"
            "property double x\nproperty double y\nproperty double z\nend_header\n"
        )
        path.write_bytes(header.encode("ascii") + value.astype("<f8").tobytes())
        return [path]

    @classmethod
    def read(cls, files: list[Path]) -> np.ndarray:
        header, _, body = files[0].read_bytes().partition(b"end_header\n")
        if b"binary_little_endian" not in header:
            raise ValueError(f"{files[0]} is not a PLY file graphvision wrote")
        return np.frombuffer(body, "<f8").reshape(-1, 3).copy()

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        from graphvision.values.pictures import scatter

        return scatter(value[:, :2])  # seen along the z axis


class HomographyPort(ArrayPort):
    """A plane-to-plane projective map: ``float64`` 3×3, finite, ``x' ~ H x``."""

    ndims = (2,)
    dtypes = (np.float64,)
    expected = "float64 3×3"

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape != (3, 3) or not np.isfinite(value).all():
            raise _fail(cls, "finite float64 3×3", value)
        return value
