"""The scheduler: run a DAG of named tasks through an executor.

Pure and small, after dask's local scheduler. It knows nothing of nodes or
caches: it gets each task's dependencies, a ``start`` function that submits a
task and returns a future, and a ``finish`` function that consumes a finished
future and says whether it succeeded.

State machine of a task::

    waiting --(all dependencies succeeded)--> running --> done | failed
    waiting --(a dependency failed, or the run is stopping)--> skipped

With ``ahead`` (an executor that passes results between its tasks itself, as
Dask does) a task starts once its dependencies have *started*; one that
completes first is held until they finish, so ``finish`` still sees every
task after its dependencies, and one whose dependency failed is skipped::

    waiting --(all dependencies started)--> running --> held --> done | failed
    running or held --(a dependency failed)--> skipped

Finished futures are handed back through a queue fed by done-callbacks, so
each completion costs O(1) however many tasks are in flight. On a failure
without ``keep_going`` no new task starts; tasks already running finish (and
their results are kept), then the loop returns.

>>> from concurrent.futures import Future
>>> def start(name):
...     future = Future(); future.set_result(name.upper()); return future
>>> order = []
>>> skipped = run_tasks({"a": set(), "b": {"a"}, "c": {"b"}}, start,
...                     lambda name, future: order.append(future.result()) or True)
>>> order, skipped
(['A', 'B', 'C'], [])
"""

from __future__ import annotations

import queue
from collections import deque
from collections.abc import Callable, Mapping, Set
from concurrent.futures import Future

__all__ = ["run_tasks"]


def run_tasks(
    dependencies: Mapping[str, Set[str]],
    start: Callable[[str], Future],
    finish: Callable[[str, Future], bool],
    *,
    keep_going: bool = False,
    run_here: Callable[[str], bool] | None = None,
    quick: Callable[[str], bool] | None = None,
    limit: int | None = None,
    ahead: bool = False,
) -> list[str]:
    """Run every task once its dependencies succeeded; return the tasks skipped.

    Parameters
    ----------
    dependencies : mapping of task name to the names it waits for
        Every dependency must itself be a key.
    start : callable
        Submits a task, returns its future (may be already done).
    finish : callable
        Called in this thread with each finished future; returns False when
        the task failed. Always called for a task's dependencies first.
    keep_going : bool
        Keep starting tasks that do not depend on a failed one.
    run_here : callable, optional
        Runs and finishes a task in this thread, returning False when it
        failed. Used for the tasks ``quick`` names, one at a time; without
        ``quick``, when a task is the only one that can run. A task of
        unknown length goes to the executor even alone, so that this thread
        stays free to take Ctrl-C at once.
    quick : callable, optional
        Whether a task is known to take less time than a hand-off to a worker
        costs (it then runs in this thread: a fan-out of tiny tasks gains
        nothing from threads but the hand-offs).
    limit : int, optional
        At most this many tasks with the executor at once; the other ready
        tasks wait here, so that what the first ones teach ``quick`` applies
        to the rest. Ready tasks still start after a failure: only tasks that
        become ready later do not.
    ahead : bool
        Start a task as soon as its dependencies have started, not finished
        (for an executor that passes results from task to task itself). A
        task that completes before a dependency has finished waits for it; one
        whose dependency failed is skipped, whatever its own future says.
    """
    waiting = {name: len(deps) for name, deps in dependencies.items()}
    unstarted = dict(waiting)  # dependencies not started yet (for ``ahead``)
    dependents: dict[str, list[str]] = {name: [] for name in dependencies}
    for name, deps in dependencies.items():
        for dep in deps:
            dependents[dep].append(name)

    finished: queue.SimpleQueue[tuple[str, Future]] = queue.SimpleQueue()
    here: list[str] = []  # started, to run in this thread (``run_here``)
    # Tasks held back until their dependencies finished come back to the loop here.
    finished_here: list[tuple[str, Future]] = []
    held: dict[str, Future] = {}  # started ahead, done before a dependency finished
    ready: deque[str] = deque()  # may start; not started yet (``limit``)
    handed: set[str] = set()  # with the executor now
    started: set[str] = set()
    blocked: set[str] = set()
    stopping = False
    running = 0

    def report_to_loop(name: str) -> Callable[[Future], None]:
        return lambda done: finished.put((name, done))

    def launch() -> None:
        """Start ready tasks: in this thread when quick (without ``quick``: when alone), one
        at a time, so that what each one takes is known before the next is placed; else
        while under ``limit``."""
        nonlocal running
        while ready:
            name = ready[0]
            if run_here is not None and (
                quick(name) if quick is not None else (running == 0 and len(ready) == 1)
            ):
                if here:  # one is waiting to run here: it may show the next is not quick
                    return
                ready.popleft()
                started.add(name)
                running += 1
                here.append(name)
                continue
            if limit is not None and len(handed) >= limit:
                return
            ready.popleft()
            started.add(name)
            handed.add(name)
            running += 1
            future = start(name)
            future.add_done_callback(report_to_loop(name))
            if ahead and not (future.done() and future.exception() is not None):
                for child in dependents[name]:  # not after one refused at once
                    unstarted[child] -= 1
                    if unstarted[child] == 0 and child not in blocked and not stopping:
                        ready.append(child)

    def block(name: str) -> None:
        nonlocal running
        stack = [name]
        while stack:
            for child in dependents[stack.pop()]:
                if child not in blocked:
                    blocked.add(child)
                    stack.append(child)
                    if child in held:  # it ran ahead, on a value that never came
                        del held[child]
                        running -= 1

    ready.extend(name for name, count in waiting.items() if count == 0)
    launch()
    while running:
        if here:
            name = here.pop()
            assert run_here is not None  # the only way into ``here``
            succeeded = run_here(name)
        else:
            name, future = finished_here.pop() if finished_here else finished.get()
            handed.discard(name)
            if name in blocked:  # started ahead of a dependency that then failed
                running -= 1
                continue
            if waiting[name]:  # started ahead and done first: its dependencies finish first
                held[name] = future
                continue
            succeeded = finish(name, future)
        running -= 1
        if succeeded:
            for child in dependents[name]:
                waiting[child] -= 1
                if waiting[child] == 0 and child in held:
                    finished_here.append((child, held.pop(child)))
                elif (
                    waiting[child] == 0
                    and child not in blocked
                    and child not in started
                    and not stopping
                ):
                    ready.append(child)
        else:
            block(name)
            stopping = stopping or not keep_going
        launch()
    return [name for name in dependencies if name not in started or name in blocked]
