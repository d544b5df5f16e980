"""The dtype policy: how arrays from outside (files, OpenCV, imageio, scikit-image) become values.

Images read from a file and arrays a caller passes as graph inputs go through
these functions, through :meth:`~graphvision.PortType.coerce` of the port they
feed, so a ``uint8`` photo means the same whether it came from a PNG or from
``cv2.imread``:

* intensity images (:func:`to_float_image`): unsigned integers divided by
  their maximum (uint8 by 255, uint16 by 65535), bool to {0, 1}, floats kept
  when in [0, 1]; all as ``float32``; an alpha channel is dropped;
* masks (:func:`to_mask`): bool, or an array holding only 0 and one other
  value (a mask saved as 0/255 PNG);
* labels (:func:`to_labels`): any non-negative integers that fit ``int32``;
* other arrays of one declared dtype (:func:`to_dtype`): cast when no value
  can change (``numpy.can_cast(..., "safe")``).

Colour order is not guessed: OpenCV's BGR arrays must be reversed
(``array[..., ::-1]``) by the caller.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from graphvision.errors import PortValueError

__all__ = ["dtype_name", "in_unit_range", "to_dtype", "to_float_image", "to_labels", "to_mask"]

_DTYPE_NAMES: dict[np.dtype, str] = {}


def dtype_name(dtype: np.dtype) -> str:
    """``str(dtype)`` (``"float32"``), kept for NumPy's built-in dtypes in native byte order:
    NumPy builds the name in Python, 5 µs a call, and a run names several (its outputs'
    summaries, its inputs' provenance)."""
    name = _DTYPE_NAMES.get(dtype)
    if name is None:
        name = str(dtype)
        if dtype.isbuiltin == 1:  # (a structured, flexible or swapped dtype: named each time)
            _DTYPE_NAMES[dtype] = name
    return name


_ONE_BITS = int(np.float32(1.0).view(np.uint32))


def in_unit_range(array: np.ndarray) -> bool:
    """Whether every value of a ``float32`` array lies in [+0, 1], in one pass over it.

    Read as unsigned integers, the floats +0 to 1 are exactly the numbers 0 to
    ``0x3F800000``; a negative number (sign bit set), NaN and infinity all read
    as larger ones. So one integer maximum decides, where a minimum and a maximum
    took two passes (5 ms per port on a 2048² image). False also for -0.0 (a
    number with the sign bit): the caller then looks closer with the minimum and
    maximum, which accept it and say what is wrong otherwise.
    """
    return array.dtype == np.float32 and int(array.view(np.uint32).max()) <= _ONE_BITS


def _plain_array(array: Any, source: str) -> np.ndarray:
    if not isinstance(array, np.ndarray) or array.dtype.hasobject:
        raise PortValueError(f"{source} must be a numeric numpy array, got {type(array).__name__}")
    if type(array) is not np.ndarray:  # a masked array's or a matrix's values, all of them
        array = np.asarray(array)
    if array.size == 0:
        raise PortValueError(f"{source} is empty (shape {array.shape})")
    return array


def to_float_image(array: Any, *, source: str = "image", check_range: bool = True) -> np.ndarray:
    """Any image array as ``float32`` in [0, 1], gray ``H×W`` or RGB ``H×W×3``.

    Unsigned integers are divided by their maximum (uint8 by 255, uint16 by
    65535), booleans map to {0, 1}, floats must already lie in [0, 1] (unless
    ``check_range`` is False: a filter response keeps its range). Colour
    images keep RGB; an alpha channel is dropped, gray+alpha becomes gray,
    a single channel ``H×W×1`` becomes ``H×W``.

    Parameters
    ----------
    array : ndarray
        ``H×W``, ``H×W×1``, ``H×W×2`` (gray + alpha), ``H×W×3`` or ``H×W×4`` (RGBA).
    source : str
        What the array is, for messages (a file name, an input name).
    check_range : bool
        Refuse floats outside [0, 1].

    Raises
    ------
    PortValueError
        Naming ``source`` for an empty, non-numeric, out-of-range or
        wrongly shaped array (a ``ValueError``).
    """
    array = _plain_array(array, source)
    if array.ndim == 3 and array.shape[2] in (2, 4):
        array = array[..., : array.shape[2] - 1]
    if array.ndim == 3 and array.shape[2] == 1:
        array = array[..., 0]
    if array.ndim not in (2, 3) or (array.ndim == 3 and array.shape[2] != 3):
        raise PortValueError(f"{source} must be H×W (gray) or H×W×3 (RGB), got shape {array.shape}")
    if array.dtype == np.bool_:
        return array.astype(np.float32)
    if np.issubdtype(array.dtype, np.unsignedinteger):
        return (array / np.float32(np.iinfo(array.dtype).max)).astype(np.float32)
    if np.issubdtype(array.dtype, np.floating):
        if array.dtype.itemsize > 4:  # beyond float32's range is refused below, with where
            with np.errstate(over="ignore"):
                result = array.astype(np.float32)
        else:
            result = array.astype(np.float32, copy=False)
        if check_range and in_unit_range(result):
            return result
        low, high = float(np.min(result)), float(np.max(result))
        if not (np.isfinite(low) and np.isfinite(high)):
            raise _not_finite(array, source)
        if check_range and not (low >= 0.0 and high <= 1.0):
            raise PortValueError(
                f"{source} has float values in [{low:g}, {high:g}]; expected [0, 1] "
                "(divide by the maximum your data can take)"
            )
        return result
    raise PortValueError(
        f"{source} has dtype {array.dtype}; expected unsigned integers, bool or float"
    )


def _not_finite(array: np.ndarray, source: str) -> PortValueError:
    """What is wrong with a float array that is not finite as ``float32``: NaN or
    infinity of its own, or finite values (float64 and wider) beyond float32's range,
    the largest of which is named with where it is."""
    if not np.isfinite(array).all():
        return PortValueError(f"{source} has NaN or infinite values")
    index = np.unravel_index(int(np.argmax(np.abs(array))), array.shape)
    axes = ("row", "column", "channel")[: array.ndim]
    where = ", ".join(f"{axis} {i}" for axis, i in zip(axes, index, strict=True))
    limit = float(np.finfo(np.float32).max)
    return PortValueError(
        f"{source} has {array.dtype} values outside float32's range (±{limit:.4g}): "
        f"the largest, {float(array[index]):g}, is at {where}; scale the data down "
        "(divide by its maximum) before passing it"
    )


def to_mask(array: Any, *, source: str = "mask") -> np.ndarray:
    """A ``bool`` ``H×W`` mask: bool as is, or 0 and one other value (e.g. 0/255) as False/True.

    Raises
    ------
    PortValueError
        For a non-2-D array or one with more than two values, naming ``source``.
    """
    array = _plain_array(array, source)
    if array.ndim != 2:
        raise PortValueError(f"{source} must be a H×W mask, got shape {array.shape}")
    if array.dtype == np.bool_:
        return array
    values = np.unique(array)
    if values.size > 2 or (values.size == 2 and values[0] != 0) or values.min() < 0:
        shown = ", ".join(f"{v:g}" for v in values[:4].astype(float))
        raise PortValueError(
            f"{source} is not a mask: expected bool or 0 and one other value, got values "
            f"{shown}{'...' if values.size > 4 else ''}"
        )
    return array != 0


def to_labels(array: Any, *, source: str = "labels") -> np.ndarray:
    """An ``int32`` ``H×W`` label image from any integer array with labels in [0, 2³¹).

    Raises
    ------
    PortValueError
        For a non-integer array or labels outside the range, naming ``source``.
    """
    array = _plain_array(array, source)
    if not np.issubdtype(array.dtype, np.integer):
        raise PortValueError(f"{source} must hold integer labels, got dtype {array.dtype}")
    low, high = int(array.min()), int(array.max())
    if low < 0 or high > np.iinfo(np.int32).max:
        raise PortValueError(f"{source} has labels in [{low}, {high}]; expected 0 to 2³¹ - 1")
    return array.astype(np.int32, copy=False)


def to_dtype(array: Any, dtype: type) -> Any:
    """``array`` cast to ``dtype`` when the cast cannot change a value; anything else unchanged.

    Booleans are not numbers here: a bool array is left for validation to refuse.
    """
    if (
        isinstance(array, np.ndarray)
        and array.dtype != np.bool_
        and array.dtype != dtype
        and np.can_cast(array.dtype, dtype, "safe")
    ):
        return array.astype(dtype)
    return array
