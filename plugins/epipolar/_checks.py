"""Checks of the point pairs that two-view nodes take."""

from __future__ import annotations

import numpy as np

__all__: list[str] = []  # its helper is private to the family's nodes


def _pairs(a: np.ndarray, b: np.ndarray, least: int, what: str) -> None:
    if len(a) != len(b):
        raise ValueError(f"{what}: {len(a)} points in view a but {len(b)} in view b")
    if len(a) < least:
        raise ValueError(f"{what} needs at least {least} correspondences, got {len(a)}")
