"""Stale work is ended, a dying worker is survived: the studio's worker processes.

A node that spins for minutes is superseded by a newer change, or cancelled: its worker
process is killed (the node's process id, written by the node, is gone), the newer
run's values are the ones kept. A worker killed from outside (``kill -9``) or ended by
its node (``os._exit``) fails that node alone, naming it and how the process ended; the
next change runs. Nothing here waits for a node to finish by itself: a spinning node
runs for 10 minutes unless it is ended.
"""

from __future__ import annotations

import operator
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("starlette")

import graphvision as gv
from graphvision.studio.session import Session, StudioRun
from graphvision.studio.workers import NodeStoppedError, WorkerPool, how_it_ended

PLUGIN = Path(__file__).parent / "stopping_plugin.py"
MINUTES = 600.0


@pytest.fixture(scope="module")
def registry() -> gv.Registry:
    return gv.discover([PLUGIN])


def _graph(pidfile: Path) -> gv.Graph:
    graph = gv.Graph("spinning")
    graph.input("x", "Float", default=1.0)
    graph.add("spin", "studio_test.spin", x="x",
              params={"seconds": MINUTES, "pidfile": str(pidfile)})  # fmt: skip
    graph.add("exit", "studio_test.exit", x="spin", params={"status": 0})
    graph.output("y", "exit")
    return graph


@pytest.fixture
def spinning(registry, tmp_path: Path) -> Iterator[tuple[Session, Path]]:
    pidfile = tmp_path / "pid"
    session = Session(_graph(pidfile), registry, workers=1)
    yield session, pidfile
    session.close()


def _spinning_pid(session: Session, run: StudioRun, pidfile: Path) -> int:
    """The process id of the worker running ``spin`` (once the node has started)."""
    deadline = time.monotonic() + 120  # a cold worker imports numpy and the plugins first
    while not pidfile.exists() or not pidfile.read_text():
        assert run.status == "running" and time.monotonic() < deadline, run.error
        time.sleep(0.02)
    pid = int(pidfile.read_text())
    assert session.pool is not None and session.pool.running() == {pid: run.id}
    pidfile.unlink()
    return pid


def _ended(pid: int) -> bool:
    """Whether process ``pid`` no longer runs (gone, or a zombie waiting to be reaped)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return True
    return state in ("Z", "X")


def _ends_soon(pid: int) -> bool:
    """Within ten seconds (a loaded machine reaps slowly), not the ten minutes it would spin."""
    deadline = time.monotonic() + 10.0
    while not _ended(pid):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def test_a_superseded_node_has_its_worker_ended_and_the_newer_values_are_shown(
    spinning,
) -> None:
    session, pidfile = spinning
    stale = session.start()
    pid = _spinning_pid(session, stale, pidfile)
    newer = session.change({"spin.seconds": 0.5})
    assert stale.killed == [pid]
    assert _ends_soon(pid)  # the stale node keeps no CPU busy
    session.wait()
    assert stale.status == "superseded" and stale.values == {}
    assert stale.nodes["spin"]["status"] == "stopped"
    assert newer.status == "done", newer.error
    assert newer.metrics == {"y": 1.5}  # x + seconds of the newer value
    assert newer.values[("spin", "out")] == 1.5
    assert session.latest_with_values() is newer


def test_the_cancel_button_ends_the_running_node(spinning) -> None:
    session, pidfile = spinning
    slow = session.start()
    pid = _spinning_pid(session, slow, pidfile)
    assert session.cancel() is slow
    assert _ends_soon(pid)
    session.wait()
    assert slow.status == "cancelled" and slow.values == {}
    assert slow.nodes["spin"]["status"] == "stopped"
    assert "exit" not in slow.nodes or slow.nodes["exit"]["status"] == "queued"
    again = session.change({"spin.seconds": 0.0})  # a new worker took the killed one's place
    session.wait()
    assert again.status == "done" and again.metrics == {"y": 1.0}


def test_a_worker_killed_from_outside_fails_its_node_alone(spinning) -> None:
    session, pidfile = spinning
    run = session.start()
    pid = _spinning_pid(session, run, pidfile)
    os.kill(pid, signal.SIGKILL)
    session.wait()
    assert run.status == "failed"
    assert run.nodes["spin"]["status"] == "failed"
    assert re.match(r"node 'spin' \(op studio_test.spin\) failed", run.nodes["spin"]["error"])
    assert re.search(
        rf"the worker process running this node \(pid {pid}\) died: killed by signal 9 "
        r"\(SIGKILL\); a new worker took its place",
        run.error,
    )
    after = session.change({"spin.seconds": 0.25})  # the session goes on
    session.wait()
    assert after.status == "done" and after.metrics == {"y": 1.25}


def test_a_node_that_ends_its_own_worker(registry, tmp_path: Path) -> None:
    graph = _graph(tmp_path / "pid").with_overrides({"spin.seconds": 0.0, "exit.status": 3})
    session = Session(graph, registry, workers=1)
    try:
        broken = session.start()
        session.wait()
        assert broken.status == "failed" and broken.nodes["exit"]["status"] == "failed"
        assert broken.metrics == {}
        assert re.match(
            r"node 'exit' \(op studio_test.exit\) failed.*died: exited with status 3",
            broken.nodes["exit"]["error"],
        )
        mended = session.change({"exit.status": 0})
        session.wait()
        assert mended.status == "done" and mended.metrics == {"y": 1.0}
    finally:
        session.close()


def test_how_a_worker_ended_in_words() -> None:
    assert how_it_ended(-9) == "killed by signal 9 (SIGKILL)"
    assert how_it_ended(-15) == "killed by signal 15 (SIGTERM)"
    assert how_it_ended(3) == "exited with status 3"
    assert how_it_ended(None) == "it stopped answering"


def test_closing_the_session_ends_its_workers(spinning) -> None:
    session, pidfile = spinning
    run = session.start()
    pid = _spinning_pid(session, run, pidfile)
    session.close()
    assert _ends_soon(pid)
    session.wait()
    assert run.status == "cancelled"


def test_a_script_needs_no_main_guard_for_the_workers(tmp_path: Path) -> None:
    """Workers are fresh interpreters: they do not import the script that started them (a
    ``spawn`` worker would, and run its top level again)."""
    script = tmp_path / "tune.py"
    script.write_text(
        "import graphvision as gv\n"
        "from graphvision.studio.session import Session\n"
        f"registry = gv.discover([{str(PLUGIN)!r}])\n"
        "graph = gv.Graph('g')\n"
        "graph.input('x', 'Float', default=2.0)\n"
        "graph.add('spin', 'studio_test.spin', x='x', params={'seconds': 0.25})\n"
        "graph.output('y', 'spin')\n"
        "session = Session(graph, registry, workers=1)\n"
        "run = session.start()\n"
        "session.wait()\n"
        "print(run.status, run.metrics, run.error)\n"
        "session.close()\n"
    )
    done = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout == "done {'y': 2.25} \n"


def test_a_node_handed_over_after_its_run_ended_never_starts() -> None:
    pool = WorkerPool(1)
    try:
        assert pool.end_run(7, "its run was superseded") == []
        refused = pool.executor(7).submit(print, "never")
        with pytest.raises(NodeStoppedError, match="its run was superseded"):
            refused.result(timeout=1)
        assert pool.executor(8).submit(abs, -3).result(timeout=120) == 3  # other runs go on
    finally:
        pool.close()


@pytest.fixture(scope="module")
def pool() -> Iterator[WorkerPool]:
    workers = WorkerPool(2)
    yield workers
    workers.close()


def test_a_node_handed_over_ahead_of_its_input_runs_with_its_result(pool) -> None:
    """The studio's runs chain their nodes: a node is handed over with the task of the node
    it reads in place of its value, and runs once that value is made."""
    executor = pool.executor(1)
    assert executor.chains_tasks
    made = executor.submit(operator.add, 2, 3)
    reader = executor.submit(dict, {"x": (made.task, "out")})
    assert reader.result(timeout=120) == {"x": (5, "out")}


def test_a_node_whose_input_failed_never_runs(pool) -> None:
    executor = pool.executor(2)
    failing = executor.submit(operator.truediv, 1, 0)
    reader = executor.submit(abs, failing.task)
    with pytest.raises(ZeroDivisionError):
        failing.result(timeout=120)
    with pytest.raises(NodeStoppedError, match="a node it reads failed"):
        reader.result(timeout=10)
    assert executor.submit(abs, -4).result(timeout=120) == 4  # the worker is not lost


def test_ending_a_run_drops_its_nodes_waiting_for_their_inputs(pool) -> None:
    executor = pool.executor(3)
    slow = executor.submit(time.sleep, MINUTES)
    reader = executor.submit(abs, slow.task)
    deadline = time.monotonic() + 120
    while 3 not in pool.running().values():  # the slow node is on a worker
        assert time.monotonic() < deadline
        time.sleep(0.02)
    [pid] = pool.end_run(3, "its run was cancelled")
    with pytest.raises(NodeStoppedError, match="its run was cancelled"):
        reader.result(timeout=10)
    with pytest.raises(NodeStoppedError, match="superseded or cancelled"):
        slow.result(timeout=60)
    assert _ends_soon(pid)
