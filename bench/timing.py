"""The timing helpers of the benchmarks: best time over repeats, after a warm-up."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["InTurn", "best", "best_in_turn"]


def best(func: Callable[[], object], repeats: int = 5) -> float:
    """Seconds of the fastest of ``repeats`` calls of ``func`` (one untimed call first)."""
    func()
    fastest = float("inf")
    for _ in range(repeats):
        began = time.perf_counter()
        func()
        fastest = min(fastest, time.perf_counter() - began)
    return fastest


@dataclass(frozen=True)
class InTurn:
    """The fastest call of each side: wall seconds and CPU seconds of the whole process."""

    ours_wall: float
    theirs_wall: float
    ours_cpu: float
    theirs_cpu: float


def best_in_turn(
    ours: Callable[[], object],
    theirs: Callable[[], object],
    repeats: int = 5,
    min_seconds: float = 0.0,
    max_repeats: int = 40,
) -> InTurn:
    """The fastest call of ``ours`` and of ``theirs``, called in turn, by wall and CPU time.

    One untimed call of each first, then pairs (``ours``, ``theirs``): at least
    ``repeats``, and more while both sides together have taken less than
    ``min_seconds`` of wall time (at most ``max_repeats``). Timing the two in turn,
    rather than one block after the other, lets a spell of load on the machine fall
    on both sides alike. The CPU time is ``time.process_time``, every thread of the
    process: for code that runs on one thread it is the wall time less the moments
    other processes held the core, so it moves much less with the machine's load,
    and a thread a side started unseen would still be counted.
    """
    ours()
    theirs()
    wall = [float("inf"), float("inf")]
    cpu = [float("inf"), float("inf")]
    spent = 0.0
    pairs = 0
    while pairs < repeats or (spent < min_seconds and pairs < max_repeats):
        for side, func in enumerate((ours, theirs)):
            began, began_cpu = time.perf_counter(), time.process_time()
            func()
            seconds = time.perf_counter() - began
            cpu[side] = min(cpu[side], time.process_time() - began_cpu)
            wall[side] = min(wall[side], seconds)
            spent += seconds
        pairs += 1
    return InTurn(wall[0], wall[1], cpu[0], cpu[1])
