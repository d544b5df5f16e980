"""Structuring elements as a port type of their own (a plugin-defined type)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import AfterValidator, Field

from graphvision import ArrayPort, BinaryImage, PortValueError, node

from ..shared.params import odd

__all__ = ["Footprint", "FootprintPort", "footprint", "footprint_from_mask"]


class FootprintPort(ArrayPort):
    """A structuring element: ``bool`` 2-D, odd sides (it has a centre), at least one True."""

    ndims = (2,)
    dtypes = (np.bool_,)
    expected = "bool 2-D array with odd sides"

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape[0] % 2 == 0 or value.shape[1] % 2 == 0:
            raise PortValueError(
                f"structuring element must have odd sides so that it has a centre, "
                f"got {value.shape[0]}×{value.shape[1]}"
            )
        if not value.any():
            raise PortValueError("structuring element is empty (no True element)")
        return value


Footprint = Annotated[NDArray[np.bool_], FootprintPort]
"""The annotation of a structuring element (see :class:`FootprintPort`)."""

Side = Annotated[int, Field(ge=1, le=501, description="Side in pixels (odd)."), AfterValidator(odd)]
"""An element's side: odd so that it has a centre, refused at validation otherwise."""


@node("morphology.footprint", version=1)
def footprint(
    *,
    shape: Literal["square", "rectangle", "disk", "cross", "diamond"] = "disk",
    size: Side = 5,
    height: Side = 3,
    width: Side = 5,
) -> Footprint:
    r"""A structuring element of a standard shape.

    * ``square``: ``size × size``; ``rectangle``: ``height × width``;
    * ``disk``: pixels with :math:`u^2 + v^2 \le r^2`, :math:`r = (size - 1) / 2`;
    * ``diamond``: :math:`|u| + |v| \le r`; ``cross``: the centre row and column.

    Sides must be odd so that the element has a centre.

    Parameters
    ----------
    shape : {"square", "rectangle", "disk", "cross", "diamond"}
        The shape.
    size : int
        Odd side of a square, disk, cross or diamond.
    height, width : int
        Odd sides of a rectangle.

    Returns
    -------
    footprint : bool ndarray
    """
    if shape == "rectangle":
        return np.ones((height, width), dtype=bool)
    r = size // 2
    v, u = np.mgrid[-r : r + 1, -r : r + 1]
    if shape == "square":
        return np.ones((size, size), dtype=bool)
    if shape == "disk":
        return u * u + v * v <= r * r
    if shape == "diamond":
        return np.abs(u) + np.abs(v) <= r
    return (u == 0) | (v == 0)


@node("morphology.footprint_from_mask", version=1)
def footprint_from_mask(mask: BinaryImage) -> Footprint:
    """Use a mask (e.g. read from a file) as a structuring element, checked for a centre.

    Parameters
    ----------
    mask : BinaryImage
        Any mask with odd sides and at least one pixel set: the element itself.

    Returns
    -------
    footprint : bool ndarray (odd sides, not empty)
    """
    return FootprintPort.validate(np.ascontiguousarray(mask))
