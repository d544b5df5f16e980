"""The order of a DAG's tasks, and its cycles when it has some.

Kahn's algorithm orders the tasks; when it cannot order them all, the ones
left each wait on another one left, so following waits finds the cycles,
printed as dask prints them (``a -> b -> a``).
"""

from __future__ import annotations

import heapq
from collections.abc import Mapping, Set

__all__ = ["CycleError", "topological_order"]


class CycleError(ValueError):
    """The dependencies contain cycles; ``cycles`` lists some, each as a closed path."""

    def __init__(self, cycles: list[list[str]]) -> None:
        self.cycles = cycles
        super().__init__(
            "dependencies contain a cycle: " + "; ".join(" -> ".join(c) for c in cycles)
        )


def topological_order(dependencies: Mapping[str, Set[str]]) -> list[str]:
    """Kahn's algorithm; among ready tasks the one declared first goes first.

    >>> topological_order({"c": {"b"}, "b": {"a"}, "a": set()})
    ['a', 'b', 'c']
    >>> topological_order({"a": set(), "b": {"a"}, "c": set()})
    ['a', 'b', 'c']
    """
    index = {name: i for i, name in enumerate(dependencies)}
    waiting = {name: len(deps) for name, deps in dependencies.items()}
    dependents: dict[str, list[str]] = {name: [] for name in dependencies}
    for name, deps in dependencies.items():
        for dep in deps:
            dependents[dep].append(name)
    ready = [index[name] for name, count in waiting.items() if count == 0]
    heapq.heapify(ready)
    names = list(dependencies)
    order = []
    while ready:
        name = names[heapq.heappop(ready)]
        order.append(name)
        for child in dependents[name]:
            waiting[child] -= 1
            if waiting[child] == 0:
                heapq.heappush(ready, index[child])
    if len(order) != len(dependencies):
        raise CycleError(_cycles_left(dependencies, set(order)))
    return order


def _cycles_left(
    dependencies: Mapping[str, Set[str]], done: set[str], limit: int = 5
) -> list[list[str]]:
    """Cycles among the tasks Kahn's algorithm could not order (each starts at its least name).

    Every task left waits on another task left, so following waits from any
    of them must come back to a task already on the path: that stretch is a
    cycle. Tasks on a found cycle are not started from again.
    """
    left = {
        name: sorted(d for d in deps if d not in done)
        for name, deps in dependencies.items()
        if name not in done
    }
    cycles: list[list[str]] = []
    used: set[str] = set()
    for start in sorted(left):
        if start in used or len(cycles) >= limit:
            continue
        path, position = [start], {start: 0}
        while True:
            step = left[path[-1]][0]
            if step in position:
                cycle = path[position[step] :]
                break
            position[step] = len(path)
            path.append(step)
        used.update(path)
        first = cycle.index(min(cycle))
        closed = cycle[first:] + cycle[:first] + [min(cycle)]
        if closed not in cycles:
            cycles.append(closed)
    return cycles
