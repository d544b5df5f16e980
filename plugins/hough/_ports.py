"""The port types of what the Hough transforms find: lines and circles."""

from __future__ import annotations

from typing import Annotated, Any

import numpy as np
from numpy.typing import NDArray

from graphvision import ArrayPort, PortValueError

__all__ = ["Circles", "CirclesPort", "Lines", "LinesPort"]


class LinesPort(ArrayPort):
    r"""Lines :math:`x\cos\theta + y\sin\theta = \rho` as ``float64 N×3`` rows ``(ρ, θ, votes)``.

    :math:`\theta \in [0, \pi)` in radians, :math:`\rho` in pixels (signed),
    x the column and y the row; ``votes`` is the line's strength: for
    ``hough.lines`` its support, the length in pixels of the line covered by
    its edge points. No lines is a ``0×3`` array.
    """

    ndims = (2,)
    dtypes = (np.float64,)
    expected = "float64 N×3 (rho, theta, votes)"
    allow_empty = True

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape[1:] != (3,) or not np.isfinite(value).all():
            raise PortValueError(f"expected Lines ({cls.expected}), got shape {value.shape}")
        return value


class CirclesPort(ArrayPort):
    """Circles as ``float64 N×4`` rows ``(x, y, radius, score)``; no circles is ``0×4``."""

    ndims = (2,)
    dtypes = (np.float64,)
    expected = "float64 N×4 (x, y, radius, score)"
    allow_empty = True

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape[1:] != (4,) or not np.isfinite(value).all():
            raise PortValueError(f"expected Circles ({cls.expected}), got shape {value.shape}")
        return value


Lines = Annotated[NDArray[np.float64], LinesPort]
Circles = Annotated[NDArray[np.float64], CirclesPort]
