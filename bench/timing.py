"""The one timing helper of the benchmarks: best wall time over repeats, after a warm-up."""

from __future__ import annotations

import time
from collections.abc import Callable

__all__ = ["best"]


def best(func: Callable[[], object], repeats: int = 5) -> float:
    """Seconds of the fastest of ``repeats`` calls of ``func`` (one untimed call first)."""
    func()
    fastest = float("inf")
    for _ in range(repeats):
        began = time.perf_counter()
        func()
        fastest = min(fastest, time.perf_counter() - began)
    return fastest
