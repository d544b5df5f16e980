"""The scheduler: starting tasks ahead, in this thread, and under a limit."""

from __future__ import annotations

import threading
from concurrent.futures import Future

import pytest

from graphvision.execution.scheduler import EVERY_TASK, run_tasks

CHAIN = {"a": set(), "b": {"a"}, "c": {"b"}}


class Tasks:
    """Futures completed by a thread in a chosen order, once every task has started."""

    def __init__(self, expected: int, outcomes: list[tuple[str, object]]) -> None:
        self.futures: dict[str, Future] = {}
        self.started: list[str] = []
        self.finished: list[str] = []
        self.outcomes = outcomes
        self.all_started = threading.Event()
        self.expected = expected
        self.thread = threading.Thread(target=self.complete)
        self.thread.start()

    def start(self, name: str) -> Future:
        self.started.append(name)
        self.futures[name] = Future()
        if len(self.started) == self.expected:
            self.all_started.set()
        return self.futures[name]

    def complete(self) -> None:
        assert self.all_started.wait(10)
        for name, outcome in self.outcomes:
            if isinstance(outcome, Exception):
                self.futures[name].set_exception(outcome)
            else:
                self.futures[name].set_result(outcome)

    def finish(self, name: str, future: Future) -> bool:
        self.finished.append(name)
        return future.exception() is None


def test_a_chain_starts_at_once_and_finishes_in_dependency_order():
    tasks = Tasks(3, [("c", 3), ("b", 2), ("a", 1)])  # the last one done first
    skipped = run_tasks(CHAIN, tasks.start, tasks.finish, ahead=True)
    tasks.thread.join()
    assert tasks.started == ["a", "b", "c"]
    assert tasks.finished == ["a", "b", "c"] and skipped == []


def test_tasks_started_ahead_of_a_failure_are_skipped_whatever_they_returned():
    tasks = Tasks(3, [("c", 3), ("a", ValueError("a failed")), ("b", ValueError("a failed"))])
    skipped = run_tasks(CHAIN, tasks.start, tasks.finish, ahead=True)
    tasks.thread.join()
    assert tasks.finished == ["a"] and skipped == ["b", "c"]


def test_without_ahead_a_task_starts_after_its_dependencies_finished():
    order: list[str] = []

    def start(name: str) -> Future:
        order.append(f"start {name}")
        future: Future = Future()
        future.set_result(name)
        return future

    def finish(name: str, future: Future) -> bool:
        order.append(f"finish {name}")
        return True

    run_tasks(CHAIN, start, finish)
    assert order == ["start a", "finish a", "start b", "finish b", "start c", "finish c"]


def test_an_independent_branch_started_ahead_keeps_its_result_after_a_failure():
    graph = {"a": set(), "b": {"a"}, "x": set(), "y": {"x"}}
    tasks = Tasks(
        4, [("a", ValueError("a failed")), ("b", ValueError("a failed")), ("x", 1), ("y", 2)]
    )
    skipped = run_tasks(graph, tasks.start, tasks.finish, ahead=True)
    tasks.thread.join()
    assert sorted(tasks.finished) == ["a", "x", "y"] and skipped == ["b"]


def test_quick_tasks_run_in_this_thread_and_the_others_under_the_limit():
    fan = {f"t{k}": set() for k in range(10)}
    handed, here, most = [], [], [0]
    in_flight: list[Future] = []

    def start(name: str) -> Future:
        handed.append(name)
        future: Future = Future()
        in_flight.append(future)
        most[0] = max(most[0], sum(not f.done() for f in in_flight))
        threading.Timer(0.01, future.set_result, (name,)).start()
        return future

    def run_here(name: str) -> bool:
        here.append(name)
        return True

    quick = {f"t{k}" for k in range(5, 10)}
    skipped = run_tasks(
        fan, start, lambda name, future: True, run_here=run_here, quick=quick.__contains__, limit=2
    )
    assert skipped == [] and sorted(here) == sorted(quick)
    assert sorted(handed) == [f"t{k}" for k in range(5)] and most[0] == 2


def test_a_chain_runs_in_this_thread():
    started, here = [], []
    run_tasks(CHAIN, started.append, lambda n, f: True, run_here=lambda n: here.append(n) or True)
    assert started == [] and here == ["a", "b", "c"]


def test_nothing_starts_ahead_of_a_task_refused_at_once():
    started = []

    def start(name: str) -> Future:
        started.append(name)
        future: Future = Future()
        future.set_exception(RuntimeError("cannot send it"))
        return future

    skipped = run_tasks(CHAIN, start, lambda name, future: False, ahead=True)
    assert started == ["a"] and skipped == ["b", "c"]


def _diamond_with_failure() -> dict[str, set[str]]:
    """A graph where ``b`` fails: ``d`` reads it, ``c`` and ``e`` do not, ``f`` joins late."""
    return {
        "a": set(),
        "b": {"a"},
        "c": {"a"},
        "d": {"b"},
        "e": {"c"},
        "f": {"c", "e"},
        "g": set(),
    }


def _run_here(order: list[str], fails: str):
    return lambda name: order.append(name) or name != fails


def _never_started(name: str) -> Future:
    raise AssertionError(f"{name} was handed to the executor")


@pytest.mark.parametrize("keep_going", [False, True])
def test_every_task_here_runs_as_the_loop_would(keep_going):
    """With ``quick=EVERY_TASK`` (sync) the tasks run one by one without the loop: the same
    order, the same tasks skipped after a failure, with and without keep_going."""
    by_loop: list[str] = []
    by_one: list[str] = []
    skipped_by_loop = run_tasks(
        _diamond_with_failure(), _never_started, lambda n, f: True, keep_going=keep_going,
        run_here=_run_here(by_loop, "b"), quick=lambda name: True,
    )  # fmt: skip
    skipped_by_one = run_tasks(
        _diamond_with_failure(), _never_started, lambda n, f: True, keep_going=keep_going,
        run_here=_run_here(by_one, "b"), quick=EVERY_TASK,
    )  # fmt: skip
    assert by_one == by_loop
    assert skipped_by_one == skipped_by_loop
    expected = ["a", "g", "b", "c"] + (["e", "f"] if keep_going else [])
    assert by_one == expected
    assert skipped_by_one == (["d"] if keep_going else ["d", "e", "f"])


def test_quick_tasks_run_here_one_by_one_until_the_next_is_not_quick():
    """On threads, quick tasks run in this thread without the loop's steps; the loop takes
    over at the first task whose op is not (or no longer) known quick."""
    dependencies = {"a": set(), "b": {"a"}, "c": {"b"}, "d": {"c"}, "e": {"d"}}
    ops = {"a": "fast", "b": "fast", "c": "slow", "d": "fast", "e": "later"}
    quick, here, handed = {"fast", "later"}, [], []

    def run_here(name: str) -> bool:
        here.append(name)
        if name == "d":
            quick.discard("later")  # what a run learns: this op took long
        return True

    def start(name: str) -> Future:
        handed.append(name)
        done: Future = Future()
        done.set_result(name)
        return done

    skipped = run_tasks(
        dependencies, start, lambda name, future: True, run_here=run_here,
        quick=lambda name: ops[name] in quick, quick_ops=(ops, quick), limit=4,
    )  # fmt: skip
    assert (here, handed, skipped) == (["a", "b", "d"], ["c", "e"], [])


def test_quick_tasks_go_back_to_one_by_one_once_nothing_runs_on_the_executor():
    """After a task the executor ran, the quick tasks that follow it run one by one again,
    without the loop's steps (which ask ``quick`` about every task they place)."""
    dependencies = {f"t{k}": {f"t{k - 1}"} if k else set() for k in range(40)}
    ops = dict.fromkeys(dependencies, "fast") | {"t1": "slow", "t30": "slow"}
    quick, asked, here, handed = {"fast"}, [], [], []

    def ask(name: str) -> bool:
        asked.append(name)
        return ops[name] in quick

    def start(name: str) -> Future:
        handed.append(name)
        done: Future = Future()
        done.set_result(name)
        return done

    skipped = run_tasks(
        dependencies, start, lambda name, future: True, run_here=lambda n: here.append(n) or True,
        quick=ask, quick_ops=(ops, quick), limit=4,
    )  # fmt: skip
    assert skipped == [] and handed == ["t1", "t30"]
    assert here == [name for name in dependencies if name not in handed]
    assert asked == ["t1", "t2", "t30", "t31"]  # the loop placed these; the rest ran one by one


def test_a_fan_out_goes_back_to_one_by_one_once_its_handed_task_finished():
    """The quick tasks ready beside a task handed to the executor run through the loop only
    until that task has finished: then one by one again (the loop took every task of a
    1,000-task fan-out after one hand-off)."""
    dependencies: dict[str, set[str]] = {f"t{k}": set() for k in range(40)}
    ops = dict.fromkeys(dependencies, "fast") | {"t1": "slow"}
    quick, asked, here = {"fast"}, [], []

    def ask(name: str) -> bool:
        asked.append(name)
        return ops[name] in quick

    def start(name: str) -> Future:
        done: Future = Future()
        done.set_result(name)
        return done

    skipped = run_tasks(
        dependencies, start, lambda name, future: True, run_here=lambda n: here.append(n) or True,
        quick=ask, quick_ops=(ops, quick), limit=4,
    )  # fmt: skip
    assert skipped == [] and sorted(here) == sorted(set(dependencies) - {"t1"})
    assert set(asked) == {"t1", "t2", "t3"}  # the loop placed these; the rest ran one by one
