"""Input checks and the dtype policy shared by the built-in plugins.

Messages name the argument, what was expected and what was given (after
scikit-image's ``check_nD``); none of them is an ``assert``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from graphvision import to_float_image  # the one dtype policy lives in the engine

__all__ = [
    "MAX_VALUES",
    "all_of",
    "at_most_values",
    "check_reference_method",
    "check_same_shape",
    "check_window",
    "ordered",
    "to_float_image",
]

MAX_VALUES = 2**28
"""Most values a node may make from its parameters alone (1 GiB in float32): a generator
of ``count`` images of ``size`` × ``size`` pixels is refused beyond it before it runs."""


def check_reference_method(method: str) -> None:
    """Refuse a robust-fit ``method`` the reference does not implement (``magsac``: OpenCV's
    ``USAC_MAGSAC``), for a direct call; a run refuses it at validation already."""
    if method != "ransac":
        raise ValueError(
            f"method {method!r} is implemented by the opencv backend alone "
            "(cv2.USAC_MAGSAC): run it with backend opencv"
        )


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


def at_most_values(*names: str, limit: int = MAX_VALUES) -> Callable[..., None]:
    """A node's ``check=`` refusing parameters whose product (a name given twice is
    squared: ``at_most_values("count", "size", "size")``) exceeds ``limit`` values, naming
    the parameters, the product and its size in GiB as float32."""

    def check(**params: Any) -> None:
        values = int(np.prod([params[name] for name in names], dtype=np.float64))
        if values > limit:
            powers = {name: names.count(name) for name in names}
            formula = " × ".join(
                f"{name}={params[name]}" + ("" if power == 1 else f"^{power}")
                for name, power in powers.items()
            )
            raise ValueError(
                f"{formula} would make {values:,} values ({values * 4 / 2**30:.1f} GiB as "
                f"float32), at most {limit:,}: lower one of them"
            )

    return check


def all_of(*checks: Callable[..., None]) -> Callable[..., None]:
    """A node's ``check=`` running each of ``checks`` in turn."""

    def check(**params: Any) -> None:
        for one in checks:
            one(**params)

    return check
