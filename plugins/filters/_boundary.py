"""Boundary conditions: what a filter sees where its window leaves the image.

The course lists four: *crop* (keep only pixels whose window fits, so the
output shrinks), *wrap* ("bend the image": the image repeats periodically),
*replicate* edges, and *mirror* the image. *zero* pads with black, the
"clip filter" choice of many textbooks.

========== ========================== =============== =====================
boundary   pads ``a b c d`` as         scipy.ndimage    OpenCV
========== ========================== =============== =====================
zero       ``0 0 | a b c d | 0 0``     constant (0)     BORDER_CONSTANT
wrap       ``c d | a b c d | a b``     grid-wrap        BORDER_WRAP
replicate  ``a a | a b c d | d d``     nearest          BORDER_REPLICATE
mirror     ``b a | a b c d | d c``     reflect          BORDER_REFLECT
crop       output is the valid part   —                —
========== ========================== =============== =====================
"""

from __future__ import annotations

from typing import Literal, get_args

import numpy as np

__all__ = ["BOUNDARIES", "Boundary", "crop_valid", "scipy_mode"]

Boundary = Literal["mirror", "replicate", "wrap", "zero", "crop"]
BOUNDARIES: tuple[str, ...] = get_args(Boundary)

_SCIPY = {
    "zero": "constant",
    "wrap": "grid-wrap",
    "replicate": "nearest",
    "mirror": "reflect",
    "crop": "nearest",
}


def scipy_mode(boundary: str) -> str:
    """The ``scipy.ndimage`` mode for a boundary (crop filters with any mode, then crops)."""
    return _SCIPY[boundary]


def crop_valid(filtered: np.ndarray, window: tuple[int, int]) -> np.ndarray:
    """Keep the pixels whose whole window lies in the image (window centred at ``k // 2``)."""
    (kh, kw) = window
    top, left = kh // 2, kw // 2
    return filtered[
        top : filtered.shape[0] - (kh - 1 - top), left : filtered.shape[1] - (kw - 1 - left)
    ]
