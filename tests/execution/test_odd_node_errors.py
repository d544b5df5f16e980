"""Whatever a node raises is that node's error, the same on every executor (FIX6).

An exception that pickles in the worker and does not unpickle in the client (a class whose
``__reduce__`` names what only a worker has, a ``__setstate__`` that raises) broke the process
pool (reported as the worker dying, the node run twice) and reached the client as its bytes on
Dask; a ``BaseException`` of a node's own (``class Stop(BaseException)``) escaped the engine
with a traceback on ``sync`` and ``threads`` and hung Dask; ``SystemExit`` killed Dask's
workers; a ``KeyboardInterrupt`` a node raised itself stopped the run as Ctrl-C does. A real
Ctrl-C still stops it.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading

import pytest

import graphvision as gv
from graphvision.execution.node_raised import signalled

PLUGIN = '''import os
import signal
import sys
import threading
import time
from pathlib import Path

from graphvision import Float, node


def _rebuilt(message):
    if os.environ.get("GV_TEST_CLIENT") == str(os.getpid()):
        raise ImportError("No module named 'only_on_workers'")
    return WorkersOnly(message)


class WorkersOnly(Exception):
    def __reduce__(self):
        return (_rebuilt, (str(self),))


class BadState(Exception):
    def __setstate__(self, state):
        if os.environ.get("GV_TEST_CLIENT") == str(os.getpid()):
            raise RuntimeError("no state here")
        self.__dict__.update(state)


class Stop(BaseException):
    pass


@node("odd.workers_only")
def workers_only(*, runs: str = "") -> Float:
    """Raises an exception the client cannot unpickle; notes each run in ``runs``."""
    with open(runs, "a") as noted:
        noted.write("ran\\n")
    raise WorkersOnly("made on a worker")


@node("odd.bad_state")
def bad_state(*, runs: str = "") -> Float:
    """Raises an exception whose __setstate__ fails in the client."""
    error = BadState("state lost")
    error.detail = 1
    raise error


@node("odd.stop")
def stop(*, runs: str = "") -> Float:
    """Raises a BaseException of its own."""
    raise Stop("halt")


@node("odd.exit")
def exit_(*, runs: str = "") -> Float:
    """Calls sys.exit."""
    sys.exit(3)


@node("odd.generator_exit")
def generator_exit(*, runs: str = "") -> Float:
    """Raises GeneratorExit."""
    raise GeneratorExit("closed")


@node("odd.interrupt")
def interrupt(*, runs: str = "") -> Float:
    """Raises KeyboardInterrupt itself."""
    raise KeyboardInterrupt("from the node")


@node("odd.ctrl_c")
def ctrl_c() -> Float:
    """Is interrupted by a real Ctrl-C."""
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(10)
    return 1.0


class Locked(Exception):
    def __init__(self, message):
        super().__init__(message)
        self.lock = threading.Lock()


@node("odd.locked")
def locked(*, runs: str = "") -> Float:
    """Raises an exception that does not pickle."""
    raise Locked("holds a lock")


@node("odd.long_locked")
def long_locked(*, runs: str = "") -> Float:
    """Raises an exception that does not pickle, its message longer than Dask keeps."""
    raise Locked("y" * 12000)


@node("odd.long_plain")
def long_plain(*, runs: str = "") -> Float:
    """Raises an exception that pickles, its message longer than Dask keeps."""
    raise ValueError("z" * 12000)


@node("odd.ctrl_c_exit")
def ctrl_c_exit() -> Float:
    """Turns a real Ctrl-C into SystemExit."""
    try:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(10)
    except KeyboardInterrupt:
        raise SystemExit(4)
    return 1.0


@node("odd.ctrl_c_error")
def ctrl_c_error() -> Float:
    """Turns a real Ctrl-C into an error of its own, its context hidden."""
    try:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(10)
    except KeyboardInterrupt:
        raise ValueError("stopped") from None
    return 1.0


@node("odd.bare_interrupt")
def bare_interrupt(*, runs: str = "") -> Float:
    """Raises KeyboardInterrupt itself, with no message."""
    raise KeyboardInterrupt
'''

SAID = {  # op -> what the run says (the plugin line is added)
    "workers_only": ("WorkersOnly: made on a worker", 38),
    "bad_state": ("BadState: state lost", 46),
    "stop": ("Stop: halt", 52),
    "exit": ("SystemExit: 3", 58),
    "generator_exit": ("GeneratorExit: closed", 64),
    "interrupt": ("KeyboardInterrupt: from the node", 70),
    "locked": ("Locked: holds a lock", 90),
    # an empty message: no colon, as Python's traceback (it said 'KeyboardInterrupt:  (…)')
    "bare_interrupt": (
        "KeyboardInterrupt",
        PLUGIN.splitlines().index("    raise KeyboardInterrupt") + 1,
    ),
    # Dask replaced an exception whose text is over 10,000 characters with "Long error
    # message" (its type and line lost; found by TRY45)
    "long_locked": (
        "Locked: " + "y" * 12000,
        PLUGIN.splitlines().index('    raise Locked("y" * 12000)') + 1,
    ),
    "long_plain": (
        "ValueError: " + "z" * 12000,
        PLUGIN.splitlines().index('    raise ValueError("z" * 12000)') + 1,
    ),
}


@pytest.fixture(scope="module")
def plugin(tmp_path_factory):
    path = tmp_path_factory.mktemp("odd") / "odd_nodes.py"
    path.write_text(PLUGIN)
    return gv.discover([path]), path.resolve()


@pytest.fixture(scope="module")
def dask_executor():
    pytest.importorskip("distributed", reason="Dask is an optional extra: graphvision[dask]")
    from graphvision.execution.dask import DaskExecutor

    executor = DaskExecutor(workers=1, threads_per_worker=2)
    yield executor
    executor.shutdown()


@pytest.fixture(params=["sync", "threads", "processes", "dask"])
def executor(request):
    if request.param == "dask":
        return request.getfixturevalue("dask_executor")
    return request.param


@pytest.mark.parametrize("op", sorted(SAID))
def test_a_node_error_is_the_nodes_on_every_executor(plugin, executor, op, tmp_path, monkeypatch):
    monkeypatch.setenv("GV_TEST_CLIENT", str(os.getpid()))  # where the odd ones do not unpickle
    registry, path = plugin
    runs = tmp_path / "runs.txt"
    graph = gv.Graph("odd")
    graph.output("out", graph.add("x", f"odd.{op}", {"runs": str(runs)}))
    with pytest.raises(gv.RunError) as caught:
        gv.run(graph, registry, executor=executor, cache=None)
    said, line = SAID[op]
    assert str(caught.value.failures["x"]).splitlines()[0] == (
        f"node 'x' (op odd.{op}) failed: {said} ({path}:{line})"
    )
    (node,) = (n for n in caught.value.record.nodes if n.name == "x")
    assert node.error == f"{said} ({path}:{line})"
    if op == "workers_only" and executor == "processes":  # not a worker that died, run again
        assert runs.read_text() == "ran\n"  # (Dask runs a task that raised again: retries)


@pytest.mark.parametrize("op", ["ctrl_c", "ctrl_c_exit", "ctrl_c_error"])
def test_a_real_ctrl_c_in_a_node_still_stops_the_run(plugin, op):
    """Also when the node's code turns it into SystemExit or an error of its own: that was
    the node's failure on sync (exit 1), a stop on threads (found by TRY45b)."""
    registry, _ = plugin
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        graph = gv.Graph("odd")
        graph.output("out", graph.add("x", f"odd.{op}"))
        with pytest.raises(KeyboardInterrupt) as caught:
            gv.run(graph, registry, executor="sync", cache=None)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert not isinstance(caught.value, gv.RunError)


def _caught(raising) -> KeyboardInterrupt:
    try:
        raising()
    except KeyboardInterrupt as error:
        return error
    raise AssertionError("nothing raised")


def _raise_own() -> None:
    raise KeyboardInterrupt("own")


def _signalled_in_a_loop() -> None:
    os.kill(os.getpid(), signal.SIGINT)
    while True:
        pass


def _caught_and_raised_again() -> None:
    try:
        _signalled_in_a_loop()
    except KeyboardInterrupt:
        raise KeyboardInterrupt("cleaned up") from None


@pytest.mark.parametrize("handler", ["default", "python"])
def test_a_signal_is_told_from_a_raise(handler):
    def python_handler(signum, frame):
        raise KeyboardInterrupt

    installed = signal.default_int_handler if handler == "default" else python_handler
    previous = signal.signal(signal.SIGINT, installed)
    try:
        assert not signalled(_caught(_raise_own))
        assert signalled(_caught(_signalled_in_a_loop))
        assert signalled(_caught(_caught_and_raised_again))  # the Ctrl-C is its context
        found = []
        thread = threading.Thread(target=lambda: found.append(signalled(_caught(_raise_own))))
        thread.start()
        thread.join()
        assert found == [False]  # a signal raises in the main thread only
    finally:
        signal.signal(signal.SIGINT, previous)


def test_a_stop_by_a_python_handler_is_told_where_ctrl_c_is_ignored():
    """A command started in the background ignores Ctrl-C; its SIGTERM still stops it."""

    def terminate(signum, frame):
        raise KeyboardInterrupt("terminated")

    def signalled_in_a_loop() -> None:
        os.kill(os.getpid(), signal.SIGTERM)
        while True:
            pass

    previous = (
        signal.signal(signal.SIGINT, signal.SIG_IGN),
        signal.signal(signal.SIGTERM, terminate),
    )
    try:
        assert signalled(_caught(signalled_in_a_loop))
        assert not signalled(_caught(_raise_own))  # a node's own, where Ctrl-C cannot come
    finally:
        signal.signal(signal.SIGINT, previous[0])
        signal.signal(signal.SIGTERM, previous[1])


UNGUARDED = """
import graphvision as gv

graph = gv.Graph("unguarded")
graph.output("out", graph.add("x", "odd.stop"))
try:
    gv.run(graph, gv.discover([{plugin!r}]), executor="processes", workers=2, cache=None)
except gv.RunError as error:
    print(error)
"""


def test_a_script_without_the_main_guard_says_so_once_without_tracebacks(plugin, tmp_path):
    """Each worker the fork server starts imports the client's script; one without
    ``if __name__ == "__main__":`` ran its work again there, and each such worker printed a
    traceback (90 lines each, 180 for one node on two workers)."""
    script = tmp_path / "unguarded.py"
    script.write_text(UNGUARDED.format(plugin=str(plugin[1])))
    done = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=120
    )
    assert "Traceback" not in done.stderr, done.stderr
    assert done.stdout.count(f'{script} has no `if __name__ == "__main__":`') == 1, done.stdout
