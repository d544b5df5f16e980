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
from collections.abc import Callable, Mapping, Sequence, Set
from concurrent.futures import Future
from itertools import compress
from operator import not_

__all__ = ["EVERY_TASK", "count_dependencies", "run_tasks"]


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
    counted: tuple[Mapping[str, int], Mapping[str, Sequence[str]]] | None = None,
    quick_ops: tuple[Mapping[str, str], Set[str]] | None = None,
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
    counted : (waiting, dependents), optional
        How many dependencies each task has and each task's dependents, as
        :func:`count_dependencies` makes them from ``dependencies``, made once
        for many runs (a compiled graph's schedule keeps them).
    quick_ops : (op of each task, the quick ops), optional
        What ``quick`` says, read without a call: a task is quick when its op is in
        the set (read as it changes). The tasks then run one by one in this thread,
        without the loop, as long as the next is quick; the loop takes over at the
        first that is not, and hands back when none is running and the next is quick.
    """
    waiting, dependents = counted or count_dependencies(dependencies)
    loop = _Loop(dependencies, start, finish, keep_going, run_here, quick, limit, ahead)
    loop.waiting, loop.dependents = dict(waiting), dependents
    loop.ready.extend(compress(loop.waiting, map(not_, loop.waiting.values())))  # (in C)
    fast = None if quick is EVERY_TASK else quick_ops
    if run_here and (fast or quick is EVERY_TASK):
        loop.rejoin = True  # the loop hands quick tasks back when nothing else is running
        while not _one_by_one(loop, run_here, fast):
            if ahead:  # none is running: every task started has finished
                loop.unstarted = dict(loop.waiting)
            loop.launch()
            while loop.running:
                loop.step()
            if not loop.ready:
                break
    else:
        loop.unstarted = dict(loop.waiting)  # (only ``ahead`` reads it)
        loop.launch()
        while loop.running:
            loop.step()
    return loop.skipped(dependencies)


def EVERY_TASK(name: str) -> bool:  # a constant that is a function
    """``quick`` when every task runs in this thread (``sync`` without time limits): the
    tasks then run one by one, in the order the loop would give them, without the loop."""
    return True


def count_dependencies(
    dependencies: Mapping[str, Set[str]],
) -> tuple[dict[str, int], dict[str, list[str]]]:
    """How many dependencies each task has, and each task's dependents."""
    waiting = {name: len(deps) for name, deps in dependencies.items()}
    dependents: dict[str, list[str]] = {name: [] for name in dependencies}
    for name, deps in dependencies.items():
        for dep in deps:
            dependents[dep].append(name)
    return waiting, dependents


def _one_by_one(
    loop: _Loop,
    run_here: Callable[[str], bool],
    quick_ops: tuple[Mapping[str, str], Set[str]] | None,
) -> bool:
    """:func:`run_tasks` while the next task is quick (every task without ``quick_ops``):
    first in, first out, as the loop runs them (a task is ready once its dependencies
    succeeded; after a failure without ``keep_going`` the tasks ready already still run, no
    other starts), without the loop's steps. False when a task that is not quick is next:
    the loop (its state kept up to date here) goes on from there."""
    waiting, dependents, ready, started = loop.waiting, loop.dependents, loop.ready, loop.started
    blocked, stopping, ops, quick = loop.blocked, loop.stopping, *(quick_ops or ({}, set()))
    while ready:
        name = ready.popleft()
        if quick_ops is not None and ops[name] not in quick:
            ready.appendleft(name)
            loop.stopping = stopping
            return False
        started.add(name)
        if run_here(name):
            for child in dependents[name]:
                left = waiting[child] = waiting[child] - 1
                if not left and not stopping and child not in blocked:
                    ready.append(child)
            continue
        stack = [name]
        while stack:  # everything downstream of the failed task is skipped
            for child in dependents[stack.pop()]:
                if child not in blocked:
                    blocked.add(child)
                    stack.append(child)
        stopping = stopping or not loop.keep_going
    return True


class _Loop:
    """The state of one :func:`run_tasks` call and its steps (see the module docstring)."""

    def __init__(
        self,
        dependencies: Mapping[str, Set[str]],
        start: Callable[[str], Future],
        finish: Callable[[str, Future], bool],
        keep_going: bool,
        run_here: Callable[[str], bool] | None,
        quick: Callable[[str], bool] | None,
        limit: int | None,
        ahead: bool,
    ) -> None:
        self.start, self.finish, self.keep_going = start, finish, keep_going
        self.run_here, self.quick, self.limit, self.ahead = run_here, quick, limit, ahead
        self.waiting: dict[str, int] = {}  # (set by run_tasks)
        self.unstarted: dict[str, int] = {}  # dependencies not started yet (for ``ahead``)
        self.dependents: Mapping[str, Sequence[str]] = {}
        self.finished: queue.SimpleQueue[tuple[str, Future]] = queue.SimpleQueue()
        self.here: list[str] = []  # started, to run in this thread (``run_here``)
        # Tasks held back until their dependencies finished come back to the loop here.
        self.finished_here: list[tuple[str, Future]] = []
        self.held: dict[str, Future] = {}  # started ahead, done before a dependency finished
        self.ready: deque[str] = deque()  # may start; not started yet (``limit``)
        self.handed: set[str] = set()  # with the executor now
        self.started: set[str] = set()
        self.blocked: set[str] = set()
        self.stopping = False
        self.running = 0
        self.rejoin = False  # quick tasks go back to :func:`_one_by_one` when none runs

    def skipped(self, dependencies: Mapping[str, Set[str]]) -> list[str]:
        """The tasks that did not start or were skipped, in order (none, without a step per
        task, when every task started and none was blocked)."""
        if not self.blocked and len(self.started) == len(dependencies):
            return []
        return [n for n in dependencies if n not in self.started or n in self.blocked]

    def report_to_loop(self, name: str) -> Callable[[Future], None]:
        return lambda done: self.finished.put((name, done))

    def runs_here(self, name: str) -> bool:
        """Whether ``name`` runs in this thread: quick (without ``quick``: when alone)."""
        if self.run_here is None:
            return False
        if self.quick is not None:
            return self.quick(name)
        return self.running == 0 and len(self.ready) == 1

    def launch(self) -> None:
        """Start ready tasks: in this thread when quick, one at a time, so that what each
        one takes is known before the next is placed; else while under ``limit``."""
        while self.ready:
            name = self.ready[0]
            if self.runs_here(name):
                if self.here or (self.rejoin and not self.running):
                    return  # one is waiting to run here (it may show the next is not quick),
                    # or none runs: run_tasks runs them one by one again, without the steps
                self.ready.popleft()
                self.started.add(name)
                self.running += 1
                self.here.append(name)
                continue
            if self.limit is not None and len(self.handed) >= self.limit:
                return
            self.ready.popleft()
            self.hand_out(name)

    def hand_out(self, name: str) -> None:
        """Give ``name`` to the executor; with ``ahead``, its dependents may start now."""
        self.started.add(name)
        self.handed.add(name)
        self.running += 1
        future = self.start(name)
        future.add_done_callback(self.report_to_loop(name))
        if self.ahead and not (future.done() and future.exception() is not None):
            for child in self.dependents[name]:  # not after one refused at once
                self.unstarted[child] -= 1
                if self.unstarted[child] == 0 and child not in self.blocked and not self.stopping:
                    self.ready.append(child)

    def block(self, name: str) -> None:
        """Everything downstream of a failed ``name`` is skipped."""
        stack = [name]
        while stack:
            for child in self.dependents[stack.pop()]:
                if child not in self.blocked:
                    self.blocked.add(child)
                    stack.append(child)
                    if child in self.held:  # it ran ahead, on a value that never came
                        del self.held[child]
                        self.running -= 1

    def step(self) -> None:
        """Take one finished task (or run one here), release its dependents, launch more."""
        if self.here and not self.finished_here and self.finished.empty():  # (a task the
            name = self.here.pop()  # executor finished is taken first: none left, one by one)
            assert self.run_here is not None  # the only way into ``here``
            succeeded = self.run_here(name)
        else:
            name, future = self.finished_here.pop() if self.finished_here else self.finished.get()
            self.handed.discard(name)
            if name in self.blocked:  # started ahead of a dependency that then failed
                self.running -= 1
                return
            if self.waiting[name]:  # started ahead and done first: dependencies finish first
                self.held[name] = future
                return
            succeeded = self.finish(name, future)
        self.running -= 1
        if succeeded:
            self.release(name)
        else:
            self.block(name)
            self.stopping = self.stopping or not self.keep_going
        self.launch()

    def release(self, name: str) -> None:
        """``name`` succeeded: dependents whose dependencies all did may start (or finish)."""
        for child in self.dependents[name]:
            self.waiting[child] -= 1
            if self.waiting[child] == 0 and child in self.held:
                self.finished_here.append((child, self.held.pop(child)))
            elif (
                self.waiting[child] == 0
                and child not in self.blocked
                and child not in self.started
                and not self.stopping
            ):
                self.ready.append(child)
