"""A Ctrl-C that comes while the client forks a worker, or while native code calls back
into Python, stops the batch (graphvision.execution.batch_signals): its exception used to
be raised in a callback whose exceptions Python drops (``logging``'s at-fork callback,
llvmlite's object cache), and the batch ran to its end and exited 0, or crashed."""

from __future__ import annotations

import contextlib
import csv
import ctypes
import os
import signal
import subprocess
import sys
import textwrap
from collections.abc import Iterator

import pytest

from graphvision.execution.batch_signals import signals_deferred, signals_held
from graphvision.execution.worker_start import START_VARIABLE

# SIGINT is sent once, in the client, by a callback that os.fork runs before forking: as
# a Ctrl-C that comes while the client forks (its handler then runs in an at-fork callback)
DURING_FORK = """
import os
import signal

signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a shell
armed = [True]


def ctrl_c_during_fork():
    if armed:
        armed.clear()
        os.kill(os.getpid(), signal.SIGINT)


os.register_at_fork(before=ctrl_c_during_fork)
"""

WORKER = """
import multiprocessing

from graphvision.execution.file_workers import FileWorkers

workers = FileWorkers(multiprocessing.get_context("fork"))
try:
    workers.start()
except KeyboardInterrupt:
    print("interrupted")
else:
    print("went on")
finally:
    workers.shutdown()
"""

BATCH = """
import sys

import imageio.v3 as iio
import numpy as np

import graphvision as gv

folder = sys.argv[1]
files = []
for k in range(6):
    files.append(f"{folder}/in/{k}.png")
    iio.imwrite(files[-1], np.full((8, 8), 10 * k, np.uint8))
graph = gv.Graph("mean")
graph.output("score", graph.add("score", "mean.score", image=graph.input("image", "Image")))
registry = gv.discover([f"{folder}/mean.py"])
try:
    gv.run_batch(graph, files, input="image", output_dir=f"{folder}/out", registry=registry,
                 executor="processes", workers=2)
except KeyboardInterrupt:
    print("interrupted")
else:
    print("went on")
"""

MEAN_PLUGIN = '''
import numpy as np

from graphvision import Float, Image, node


@node("mean.score")
def score(image: Image) -> Float:
    """The image's mean."""
    return float(np.mean(image))
'''


def _python(script: str, *arguments: str) -> subprocess.CompletedProcess:
    environment = dict(os.environ)
    environment.pop(START_VARIABLE, None)  # forked from the client, not the fork server
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(script), *arguments],
        capture_output=True,
        text=True,
        timeout=120,
        env=environment,
    )


def test_ctrl_c_while_the_client_forks_a_worker_is_raised_once_it_is_forked():
    done = _python(DURING_FORK + WORKER)
    assert done.stdout.strip() == "interrupted", done.stderr
    assert "Exception ignored" not in done.stderr  # where it used to go


def test_ctrl_c_while_a_processes_batch_forks_its_first_worker_stops_the_batch(tmp_path):
    (tmp_path / "in").mkdir()
    (tmp_path / "mean.py").write_text(MEAN_PLUGIN)
    done = _python(DURING_FORK + BATCH, str(tmp_path))
    assert done.stdout.strip() == "interrupted", done.stderr
    with (tmp_path / "out" / "batch.csv").open() as summary:
        statuses = [row["status"] for row in csv.DictReader(summary)]
    assert len(statuses) == 6 and set(statuses) <= {"interrupted", "not run"}, statuses


@pytest.fixture
def ctrl_c() -> Iterator[None]:
    """Ctrl-C raises KeyboardInterrupt here (a pytest-xdist worker may ignore it)."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


def _from_native_code(then: list[str]) -> None:
    """A Ctrl-C inside a Python function that C calls (through ctypes), which goes on."""

    def callback() -> None:
        os.kill(os.getpid(), signal.SIGINT)
        then.append("callback went on")

    ctypes.CFUNCTYPE(None)(callback)()
    then.append("after the call")


def test_ctrl_c_inside_a_callback_from_native_code_is_raised_after_the_block(ctrl_c):
    steps: list[str] = []
    with pytest.raises(KeyboardInterrupt), signals_deferred():
        _from_native_code(steps)
        steps.append("end of the block")
    assert steps == ["callback went on", "after the call", "end of the block"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_no_signal_no_exception_and_the_handlers_are_back(ctrl_c):
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    with signals_deferred():
        assert signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    assert {s: signal.getsignal(s) for s in handlers} == handlers


def test_a_forked_process_runs_the_handler_it_would_have_run(ctrl_c):
    """A worker forked while the client defers: its Ctrl-C is its own KeyboardInterrupt."""
    with signals_deferred():
        pid = os.fork()
        if pid == 0:  # pragma: no cover - the child
            try:
                os.kill(os.getpid(), signal.SIGINT)
                for _ in range(1000):  # the handler runs at the next bytecodes
                    pass
            except KeyboardInterrupt:
                os._exit(7)
            os._exit(0)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 7


def test_a_stop_while_held_is_ignored(ctrl_c):
    with signals_held():
        os.kill(os.getpid(), signal.SIGINT)
        steps = [k for k in range(1000)]  # the handler runs at the next bytecodes
    assert steps[-1] == 999
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def _ctrl_c(steps: list[str], step: str) -> None:
    os.kill(os.getpid(), signal.SIGINT)
    [0 for _ in range(10)]  # (a call: the handler runs here)
    steps.append(step)


@pytest.mark.parametrize("nested", [False, True])
def test_insisted_a_second_ctrl_c_is_raised_at_once(ctrl_c, nested):
    """An import deferred (``insisted``) must not make a Ctrl-C wait for a body that never
    ends; deferrals within such deferrals (a plugin's import while plugins load) alike."""
    steps: list[str] = []
    inner = signals_deferred(insisted=True) if nested else contextlib.nullcontext()
    with pytest.raises(KeyboardInterrupt), signals_deferred(insisted=True), inner:
        _ctrl_c(steps, "noted")
        _ctrl_c(steps, "went on after the second")
    assert steps == ["noted"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_insisted_inside_a_deferral_that_is_not_waits_for_its_end(ctrl_c):
    """An import inside a fork's deferral: the second Ctrl-C waits for the fork to be done."""
    steps: list[str] = []
    with pytest.raises(KeyboardInterrupt), signals_deferred():
        with signals_deferred(insisted=True):
            _ctrl_c(steps, "noted")
            _ctrl_c(steps, "noted by the fork's deferral")
        steps.append("end of the fork")
    assert steps == ["noted", "noted by the fork's deferral", "end of the fork"]


DASK_WORKERS = """
import numpy  # OpenBLAS's threads: native, not Python's (the fork is refused with those)

from graphvision.execution.dask_fork import ForkedWorkers

try:
    workers = ForkedWorkers(1, 1)
except KeyboardInterrupt:
    print("interrupted")
else:
    workers.close()
    print("went on")
"""


def test_ctrl_c_while_the_dask_executor_forks_its_workers_is_raised_once_they_are_forked():
    """Blocking SIGINT in the forking thread did not keep it out of the fork's callbacks:
    the kernel gave it to another thread, and the main thread ran its handler inside
    logging's at-fork callback, which dropped the KeyboardInterrupt."""
    pytest.importorskip("distributed", reason="Dask is an optional extra: graphvision[dask]")
    done = _python(DURING_FORK + DASK_WORKERS)
    assert done.stdout.strip() == "interrupted", done.stderr
    assert "Exception ignored" not in done.stderr


PROCESS_POOL = """
from graphvision.execution.process_executor import ProcessExecutor

pool = ProcessExecutor(2)
try:
    pool.fork_workers()
    pool.submit(int).result()
except KeyboardInterrupt:
    print("interrupted")
else:
    print("went on")
finally:
    pool.shutdown()
"""


def test_ctrl_c_while_the_processes_pool_forks_its_workers_is_raised_once_they_are_forked():
    """The pool a batch with run hooks forks from the client after its first file: its
    forks' callbacks dropped the KeyboardInterrupt too."""
    done = _python(DURING_FORK + PROCESS_POOL)
    assert done.stdout.strip() == "interrupted", done.stderr
    assert "Exception ignored" not in done.stderr
