"""The timing helpers of the benchmarks: best wall time over repeats, after a warm-up."""

from __future__ import annotations

import time
from collections.abc import Callable

__all__ = ["best", "best_in_turn"]


def best(func: Callable[[], object], repeats: int = 5) -> float:
    """Seconds of the fastest of ``repeats`` calls of ``func`` (one untimed call first)."""
    func()
    fastest = float("inf")
    for _ in range(repeats):
        began = time.perf_counter()
        func()
        fastest = min(fastest, time.perf_counter() - began)
    return fastest


def best_in_turn(
    ours: Callable[[], object],
    theirs: Callable[[], object],
    repeats: int = 5,
    min_seconds: float = 0.0,
    max_repeats: int = 40,
) -> tuple[float, float]:
    """Seconds of the fastest call of ``ours`` and of ``theirs``, called in turn.

    One untimed call of each first, then pairs (``ours``, ``theirs``): at least
    ``repeats``, and more while both sides together have taken less than
    ``min_seconds`` (at most ``max_repeats``). Timing the two in turn, rather
    than one block after the other, lets a spell of load on the machine fall on
    both sides alike, so the ratio of the two moves less between runs than
    either time does.
    """
    ours()
    theirs()
    fastest = [float("inf"), float("inf")]
    spent = 0.0
    pairs = 0
    while pairs < repeats or (spent < min_seconds and pairs < max_repeats):
        for side, func in enumerate((ours, theirs)):
            began = time.perf_counter()
            func()
            seconds = time.perf_counter() - began
            fastest[side] = min(fastest[side], seconds)
            spent += seconds
        pairs += 1
    return fastest[0], fastest[1]
