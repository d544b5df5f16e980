"""Input checks and the dtype policy shared by the built-in plugins.

Messages name the argument, what was expected and what was given (after
scikit-image's ``check_nD``); none of them is an ``assert``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["check_same_shape", "check_window", "to_float_image"]


def to_float_image(array: np.ndarray, *, source: str = "image") -> np.ndarray:
    """The one dtype policy: any image array to ``float32`` in [0, 1].

    Unsigned integers are divided by their maximum (uint8 by 255, uint16 by
    65535), booleans map to {0, 1}, floats must already lie in [0, 1]. Colour
    images keep RGB; an alpha channel is dropped, gray+alpha becomes gray.

    Raises
    ------
    ValueError
        Naming ``source`` for an empty, non-numeric, out-of-range or
        wrongly shaped array.
    """
    array = np.asarray(array)
    if array.size == 0:
        raise ValueError(f"{source} is empty (shape {array.shape})")
    if array.ndim == 3 and array.shape[2] in (2, 4):
        array = array[..., : array.shape[2] - 1]
        if array.shape[2] == 1:
            array = array[..., 0]
    if array.ndim not in (2, 3) or (array.ndim == 3 and array.shape[2] != 3):
        raise ValueError(f"{source} must be H×W (gray) or H×W×3 (RGB), got shape {array.shape}")
    if array.dtype == np.bool_:
        return array.astype(np.float32)
    if np.issubdtype(array.dtype, np.unsignedinteger):
        return (array / np.float32(np.iinfo(array.dtype).max)).astype(np.float32)
    if np.issubdtype(array.dtype, np.floating):
        result = array.astype(np.float32, copy=False)
        low, high = float(np.min(result)), float(np.max(result))
        if not (low >= 0.0 and high <= 1.0):
            raise ValueError(f"{source} has float values in [{low:g}, {high:g}]; expected [0, 1]")
        return result
    raise ValueError(f"{source} has dtype {array.dtype}; expected unsigned integers, bool or float")


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
