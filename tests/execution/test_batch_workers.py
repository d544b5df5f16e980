"""How a processes batch's workers start (graphvision.execution.worker_start): forked from
the client when nothing else runs beside it, else from the fork server, which takes the
client's path; and what a worker that cannot start again does to the file it ran."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
from types import SimpleNamespace

import pytest

from graphvision.execution.executors import WorkerDiedError, make_executor
from graphvision.execution.worker_start import fork_context


def _no_parallel_layer(monkeypatch) -> None:
    """As if numba's threading layer had not started: an earlier test in this process may
    have run a parallel kernel (the children here run no numba code)."""
    parallel = sys.modules.get("numba.np.ufunc.parallel")
    if parallel is not None:
        monkeypatch.setattr(parallel, "_is_initialized", False, raising=False)


@pytest.fixture
def alone(monkeypatch):
    """No thread but this one (earlier tests of this process may have left some)."""
    monkeypatch.setattr(threading, "enumerate", lambda: [threading.current_thread()])
    _no_parallel_layer(monkeypatch)


def test_workers_are_forks_of_the_client_when_no_other_thread_runs(alone):
    pool = make_executor("processes", 1)
    try:
        assert pool.fork_workers()  # type: ignore[attr-defined]
        assert pool.submit(os.getppid).result(timeout=60) == os.getpid()  # not the server's
    finally:
        pool.shutdown()


def test_a_forked_worker_ends_on_sigterm_without_the_clients_handler(alone):
    before = signal.signal(signal.SIGTERM, lambda *_: None)  # as the command line's
    pool = make_executor("processes", 1)
    try:
        assert pool.fork_workers()  # type: ignore[attr-defined]
        assert pool.submit(signal.getsignal, signal.SIGTERM).result(timeout=60) == signal.SIG_DFL
    finally:
        pool.shutdown()
        signal.signal(signal.SIGTERM, before)


def test_the_client_is_not_forked_beside_another_thread_or_when_told_not_to(monkeypatch):
    here = threading.current_thread()
    user = SimpleNamespace(name="user-thread")  # may hold a lock the child keeps for good
    _no_parallel_layer(monkeypatch)
    monkeypatch.setattr(threading, "enumerate", lambda: [here])
    assert fork_context() is not None
    monkeypatch.setattr(threading, "enumerate", lambda: [here, user])
    assert fork_context() is None
    monkeypatch.setattr(threading, "enumerate", lambda: [here])
    started = SimpleNamespace(_is_initialized=True)  # numba's threading layer has threads
    monkeypatch.setitem(sys.modules, "numba.np.ufunc.parallel", started)
    assert fork_context() is None
    _no_parallel_layer(monkeypatch)
    monkeypatch.setenv("GRAPHVISION_WORKER_START", "forkserver")
    assert fork_context() is None


def test_the_fork_server_takes_the_clients_path(monkeypatch):
    from graphvision.execution.worker_start import _encoded

    monkeypatch.setattr(sys, "excepthook", sys.excepthook)  # _preload sets the server's
    from graphvision.execution import _preload

    monkeypatch.setattr(sys, "path", [*sys.path, "/nowhere/b5-client-folder"])
    sent = _encoded([], ())
    monkeypatch.setattr(sys, "path", sys.path[:-1])  # as the server's, without the folder
    _preload.start_batch(sent)
    assert sys.path[-1] == "/nowhere/b5-client-folder"  # the plugin index's key agrees


class _NoStart:
    """A pool whose workers cannot start: the fork server was killed."""

    def submit(self, *args):
        raise EOFError("unexpected EOF")

    def shutdown(self, wait=True, *, cancel_futures=False):
        return None


def test_a_dead_worker_whose_retry_cannot_start_fails_its_task_and_hangs_nothing(
    alone, monkeypatch
):
    pool = make_executor("processes", 1)
    try:
        assert pool.fork_workers()  # type: ignore[attr-defined]
        assert pool.submit(os.getpid).result(timeout=60)  # the worker runs
        monkeypatch.setattr(pool, "_new_pool", lambda workers=0: _NoStart())
        died = pool.submit(os._exit, 1)  # the worker dies; its retry cannot start
        with pytest.raises(WorkerDiedError, match=r"no worker could start again .*unexpected EOF"):
            died.result(timeout=60)
        with pytest.raises(WorkerDiedError, match="no worker process could start"):
            pool.submit(os.getpid).result(timeout=60)
    finally:
        monkeypatch.undo()
        pool.shutdown(wait=False)


SLOW_PRELOAD = """
import os, pathlib, time
here = pathlib.Path(os.environ["B5_MARKS"])
(here / "importing").write_text("")
for _ in range(600):  # until the test has sent its Ctrl-C
    if (here / "go").exists():
        break
    time.sleep(0.05)
(here / "imported").write_text("")
"""


def test_ctrl_c_while_the_fork_server_imports_prints_no_traceback(tmp_path, capfd, monkeypatch):
    from multiprocessing import forkserver

    from graphvision.execution.worker_start import _ensure_running

    (tmp_path / "slow_preload_b5.py").write_text(SLOW_PRELOAD)
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))  # the server's own path
    monkeypatch.setenv("B5_MARKS", str(tmp_path))
    server = forkserver.ForkServer()
    server.set_forkserver_preload(["slow_preload_b5", "graphvision.execution._preload"])
    _ensure_running(server)
    pid = server._forkserver_pid
    try:
        _wait_for(lambda: (tmp_path / "importing").exists())
        os.kill(pid, signal.SIGINT)  # Ctrl-C reaches the client's whole process group
        (tmp_path / "go").write_text("")
        _wait_for(lambda: (tmp_path / "imported").exists() or os.waitpid(pid, os.WNOHANG)[0])
    finally:
        with contextlib.suppress(ChildProcessError):  # unless it ended (and was reaped)
            if os.waitpid(pid, os.WNOHANG)[0] == 0:
                os.kill(pid, signal.SIGTERM)
                os.waitpid(pid, 0)
        os.close(server._forkserver_alive_fd)
    err = capfd.readouterr().err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert (tmp_path / "imported").exists()  # it went on importing


def _wait_for(condition) -> bool:
    for _ in range(600):
        if condition():
            return True
        time.sleep(0.05)
    raise AssertionError("waited 30 s")
