"""A batch's own executor is shut down beside its summary, and its errors still reach the
batch's caller."""

from __future__ import annotations

import threading

import pytest

from graphvision.execution.closing import Closing


class Pool:
    def __init__(self, error: BaseException | None = None) -> None:
        self.error, self.thread, self.closed = error, "", False
        self.release = threading.Event()

    def shutdown(self) -> None:
        self.thread = threading.current_thread().name
        assert self.release.wait(30)
        if self.error is not None:
            raise self.error
        self.closed = True


def test_the_shutdown_runs_beside_the_caller_and_is_over_when_wait_returns():
    pool = Pool()
    closing = Closing(pool)
    assert closing.is_alive() and not pool.closed  # the caller goes on meanwhile
    pool.release.set()
    closing.wait()
    assert pool.closed and pool.thread == "graphvision-pool-shutdown"
    assert not closing.is_alive()


def test_what_the_shutdown_raised_is_raised_by_wait():
    pool = Pool(OSError("a worker would not end"))
    closing = Closing(pool)
    pool.release.set()
    with pytest.raises(OSError, match="a worker would not end"):
        closing.wait()
