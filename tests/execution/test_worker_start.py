"""Worker processes forked from the fork server (graphvision.execution.worker_start): they
write where the client's output goes now and see its environment as it is now."""

from __future__ import annotations

import os
import sys
import tempfile

from graphvision.execution.executors import make_executor


def _say(text: str) -> int:
    print(f"out: {text}", flush=True)
    print(f"err: {text}", file=sys.stderr, flush=True)
    return os.getpid()


def _variable(name: str) -> str | None:
    return os.environ.get(name)


def _captured(pool, text: str) -> tuple[bytes, bytes]:
    """What a task on ``pool`` printed, the client's stdout and stderr redirected first."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        saved = os.dup(1), os.dup(2)
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(out.fileno(), 1)
        os.dup2(err.fileno(), 2)
        try:
            pool.submit(_say, text).result(timeout=120)
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
        out.seek(0)
        err.seek(0)
        return out.read(), err.read()


def test_a_worker_writes_where_the_clients_output_goes_when_it_starts():
    first = make_executor("processes", 1)  # the server starts with the output as it was
    first.submit(os.getpid).result(timeout=120)
    first.shutdown()
    pool = make_executor("processes", 1)
    try:
        out, err = _captured(pool, "hello")
    finally:
        pool.shutdown()
    assert out == b"out: hello\n"
    assert err == b"err: hello\n"


def test_a_worker_sees_the_clients_environment_when_it_starts(monkeypatch):
    first = make_executor("processes", 1)
    first.submit(os.getpid).result(timeout=120)  # the server exists before the variable
    first.shutdown()
    monkeypatch.setenv("GRAPHVISION_TEST_WORKER_VARIABLE", "set after the server started")
    pool = make_executor("processes", 1)
    try:
        seen = pool.submit(_variable, "GRAPHVISION_TEST_WORKER_VARIABLE").result(timeout=120)
    finally:
        pool.shutdown()
    assert seen == "set after the server started"
