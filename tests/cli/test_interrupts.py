"""Dying workers, Ctrl-C and kill -9: one node lost at most, nothing half-written, no traceback."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import graphvision as gv

from ..conftest import TOY

SLOW = """\
name: slow
inputs:
  x: {type: Float, default: 1.0}
nodes:
  a: {op: toy.sleep, in: {x: x}, params: {seconds: 30}}
  b: {op: toy.sleep, in: {x: x}, params: {seconds: 30}}
outputs: {a: a, b: b}
"""


def _graph(marker: Path, times: int) -> gv.Graph:
    graph = gv.Graph("dying")
    x = graph.input("x", "Float", default=1.0)
    dying = graph.add("dying", "toy.die_once", x=x, params={"marker": str(marker), "times": times})
    healthy = graph.add("healthy", "toy.sleep", x=x, params={"seconds": 1.0})
    graph.output("dying", dying)
    graph.output("healthy", healthy)
    return graph


def test_a_dying_worker_costs_one_retry_and_no_healthy_node(registry, tmp_path):
    result = gv.run(_graph(tmp_path / "m", 1), registry, executor="processes", workers=2)
    assert (tmp_path / "m").read_text() == "1"  # it died once
    assert result.outputs == {"dying": 2.0, "healthy": 1.0}


def test_a_worker_that_dies_again_fails_only_its_node(registry, tmp_path):
    with pytest.raises(gv.RunError) as caught:
        gv.run(_graph(tmp_path / "m", 5), registry, executor="processes", keep_going=True)
    assert list(caught.value.failures) == ["dying"]
    assert (  # os._exit(1) in the node, each time
        "died (it exited with status 1: something in the node ended the process), "
        "and again when retried alone" in str(caught.value.failures["dying"])
    )
    assert caught.value.result.outputs["healthy"] == 1.0


def _start(tmp_path: Path, executor: str) -> subprocess.Popen:
    (tmp_path / "slow.yaml").write_text(SLOW)
    command = [sys.executable, "-m", "graphvision", "run", str(tmp_path / "slow.yaml")]
    command += ["--plugins", str(TOY), "--executor", executor, "--no-cache", "--progress"]
    command += ["-d", str(tmp_path / "out")]
    # started as a shell starts a command: Ctrl-C delivered (a pytest-xdist worker may run
    # with SIGINT ignored, and a child would inherit that)
    process = subprocess.Popen(
        command,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    assert process.stderr is not None
    line = process.stderr.readline()  # "running slow: 2 node(s) to compute"
    assert line.startswith("running slow"), line
    time.sleep(1.0)  # the nodes are running
    return process


@pytest.mark.parametrize("executor", ["threads", "processes"])
def test_ctrl_c_exits_130_with_one_line_and_nothing_written(tmp_path, executor):
    process = _start(tmp_path, executor)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=30)
    assert process.returncode == 130
    assert err.strip().startswith("interrupted after") and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out").exists()  # the folder made for the run is gone, still empty


def test_sigterm_stops_a_run_as_ctrl_c_does_and_exits_143(tmp_path):
    """kill, timeout, docker stop and batch schedulers send SIGTERM: the run stops as it
    does on Ctrl-C (one line, nothing half-written) instead of dying mid-write."""
    process = _start(tmp_path, "threads")
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=30)
    assert process.returncode == 143
    assert err.strip().startswith("terminated after") and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out").exists()


def _children(pid: int) -> set[int]:
    found = set()
    for task in Path(f"/proc/{pid}/task").glob("*"):
        with open(task / "children") as stream:
            found |= {int(child) for child in stream.read().split()}
    return found


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs Linux /proc")
def test_worker_processes_exit_when_the_command_is_killed(tmp_path):
    process = _start(tmp_path, "processes")
    workers = set()
    for _ in range(240):  # the fork server is a child, its workers (once it has imported
        children = _children(process.pid)  # what they need) its children
        forked = {g for c in children for g in _children_if_alive(c)}
        workers = {c for c in children | forked if _is_worker(c)}
        if workers & forked or any(b"spawn_main" in _command(w) for w in workers):
            break
        time.sleep(0.25)
    assert workers, "no worker process found"
    process.kill()  # kill -9: no chance to clean up
    process.wait()
    for _ in range(60):
        if not any(Path(f"/proc/{w}").exists() and not _is_zombie(w) for w in workers):
            break
        time.sleep(0.25)
    assert not any(Path(f"/proc/{w}").exists() and not _is_zombie(w) for w in workers)


def _children_if_alive(pid: int) -> set[int]:
    try:
        return _children(pid)
    except OSError:
        return set()


def _command(pid: int) -> bytes:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return b""


def _is_worker(pid: int) -> bool:
    """A worker process, or the fork server the workers are forked from."""
    command = _command(pid)
    return b"spawn_main" in command or b"multiprocessing.forkserver" in command


def _is_zombie(pid: int) -> bool:
    try:
        return " Z " in Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return True


LEAKING_CLIENT = """
import multiprocessing, os, sys
from graphvision.cli.main import quiet_resource_tracker
if sys.argv[1] == "quiet":
    quiet_resource_tracker()
lock = multiprocessing.get_context("forkserver").Lock()  # a semaphore the tracker knows
os._exit(130)  # as an interrupt in the middle of making a pool leaves it
"""


def test_an_interrupt_while_a_pool_is_made_prints_no_semaphore_warning():
    """The resource tracker's 'leaked semaphore objects' warning came after Ctrl-C's line
    when the interrupt landed while the process pool was being made."""

    def stderr_of(mode: str) -> str:
        command = [sys.executable, "-c", LEAKING_CLIENT, mode]
        done = subprocess.run(command, capture_output=True, text=True, timeout=60)
        assert done.returncode == 130
        return done.stderr

    assert "leaked semaphore" in stderr_of("loud")  # the test shows the warning it removes
    assert stderr_of("quiet") == ""
