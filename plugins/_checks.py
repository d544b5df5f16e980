"""Input checks and the dtype policy shared by the built-in plugins.

Messages name the argument, what was expected and what was given (after
scikit-image's ``check_nD``); none of them is an ``assert``.
"""

from __future__ import annotations

import numpy as np

from graphvision import to_float_image  # the one dtype policy lives in the engine

__all__ = ["check_same_shape", "check_window", "to_float_image"]


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
