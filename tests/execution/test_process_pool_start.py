"""A process pool that cannot make its semaphores (a full /dev/shm: Docker's is 64 MB) says
so and where they live, on the command line without a traceback, and writes nothing."""

from __future__ import annotations

import errno
import multiprocessing.synchronize
from pathlib import Path

import pytest

from graphvision.cli.main import main
from graphvision.execution.executors import make_executor

PIPELINES = Path(__file__).parents[2] / "pipelines"


@pytest.fixture
def full_shared_memory(monkeypatch):
    def refused(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(multiprocessing.synchronize.SemLock, "__init__", refused)


def test_a_process_pool_without_room_for_its_semaphores_names_where_they_live(
    full_shared_memory,
):
    with pytest.raises(OSError) as caught:
        make_executor("processes", workers=2)
    assert caught.value.errno == errno.ENOSPC
    assert "the process pool cannot make its semaphores in /dev/shm" in str(caught.value)
    assert "No space left on device" in str(caught.value)
    assert "threads executor" in str(caught.value)


def test_the_command_line_says_so_and_writes_nothing(full_shared_memory, tmp_path, capsys):
    out = tmp_path / "out"
    pipeline = str(PIPELINES / "coins.yaml")
    code = main(["run", pipeline, "--executor", "processes", "--output-dir", str(out)])
    error = capsys.readouterr().err
    assert code == 1
    assert error.startswith("error: the process pool cannot make its semaphores in /dev/shm")
    assert "Traceback" not in error
    assert not out.exists()


def test_a_read_only_shared_memory_is_not_told_to_free_space(monkeypatch):
    def refused(*args, **kwargs):
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(multiprocessing.synchronize.SemLock, "__init__", refused)
    with pytest.raises(OSError) as caught:
        make_executor("processes", workers=2)
    assert "(Read-only file system): make it writable, or use the threads executor" in str(
        caught.value
    )
