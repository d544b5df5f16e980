"""The two-view matrices as port values: a fundamental matrix F and an essential matrix E
(3×3 float64, rank 2)."""

from __future__ import annotations

from typing import Annotated, Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from graphvision import ArrayPort, PortValueError

__all__ = [
    "EssentialPort",
    "FundamentalPort",
]


class FundamentalPort(ArrayPort):
    """A fundamental matrix: finite ``float64`` 3×3 of rank 2, ``x_b^T F x_a = 0``, unit norm."""

    ndims: ClassVar[tuple[int, ...]] = (2,)
    dtypes = (np.float64,)
    expected = "finite float64 3×3"

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape != (3, 3) or not np.isfinite(value).all():
            raise PortValueError(
                f"expected {cls.type_name()} (finite float64 3×3), got {value.shape}"
            )
        return value


class EssentialPort(FundamentalPort):
    """An essential matrix :math:`E = [t]_\\times R` (singular values 1, 1, 0)."""


Fundamental = Annotated[NDArray[np.float64], FundamentalPort]


Essential = Annotated[NDArray[np.float64], EssentialPort]
