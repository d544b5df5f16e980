"""Input checks and the dtype policy shared by the built-in plugins.

Messages name the argument, what was expected and what was given (after
scikit-image's ``check_nD``); none of them is an ``assert``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from graphvision import to_float_image  # the one dtype policy lives in the engine

__all__ = ["check_same_shape", "check_window", "ordered", "to_float_image"]


def check_same_shape(a: np.ndarray, b: np.ndarray, names: tuple[str, str] = ("a", "b")) -> None:
    """Raise ValueError naming both arguments when their shapes differ."""
    if a.shape != b.shape:
        raise ValueError(
            f"{names[0]} and {names[1]} must have the same shape, got {a.shape} and {b.shape}"
        )


def check_window(image: np.ndarray, window: tuple[int, int], what: str) -> None:
    """Raise ValueError when a ``window`` does not fit inside the image."""
    if image.shape[0] < window[0] or image.shape[1] < window[1]:
        raise ValueError(
            f"{what} {window[0]}×{window[1]} is larger than the image "
            f"{image.shape[0]}×{image.shape[1]}"
        )


def ordered(*pairs: tuple[str, str], strict: bool = False) -> Callable[..., None]:
    """A node's ``check=`` for bounds given as two parameters: for each ``(lower, upper)``
    pair of parameter names, ValueError naming both when ``lower`` exceeds ``upper`` (or,
    with ``strict``, equals it), so the pipeline is refused before anything runs. A
    parameter left at None (a bound taken from the data) is not compared."""

    def check(**params: Any) -> None:
        for lower, upper in pairs:
            low, high = params[lower], params[upper]
            if low is None or high is None:
                continue
            if low > high or (strict and low == high):
                relation = "below" if strict else "at most"
                raise ValueError(
                    f"{lower} ({low:g}) must be {relation} {upper} ({high:g}): swap them or "
                    "widen the range"
                )

    return check
