"""A node that kills its process is named (issue 29 F): the fault handler prints where every
thread was, the node's function and file among them; cache folders are the owner's only."""

from __future__ import annotations

import os
import stat
import subprocess
import sys

import numpy as np
import pytest

import graphvision as gv

CRASHING = '''
import ctypes
from graphvision import Float, node

@node("crash.segfault")
def segfault_in_a_node() -> Float:
    """Reads address 8: a segmentation fault, as a broken C extension makes."""
    return float(ctypes.c_int.from_address(8).value)
'''

PIPELINE = """version: 1
name: crashing
plugins: [crashing.py]
nodes:
  boom: {op: crash.segfault}
outputs:
  value: boom
"""


@pytest.mark.parametrize("executor", ["sync", "threads"])
def test_a_segfault_in_a_node_names_the_node_function(tmp_path, executor):
    (tmp_path / "crashing.py").write_text(CRASHING)
    (tmp_path / "p.yaml").write_text(PIPELINE)
    command = [sys.executable, "-m", "graphvision", "run", str(tmp_path / "p.yaml")]
    done = subprocess.run(
        [*command, "--no-cache", "--executor", executor],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode in (-11, 139)  # killed by SIGSEGV
    assert "Fatal Python error: Segmentation fault" in done.stderr
    assert "segfault_in_a_node" in done.stderr and "crashing.py" in done.stderr


def test_a_segfault_on_processes_fails_the_node_saying_it_crashed(tmp_path):
    """The client lives on; the node's error says how its worker ended, each time."""
    (tmp_path / "crashing.py").write_text(CRASHING)
    (tmp_path / "p.yaml").write_text(PIPELINE)
    command = [sys.executable, "-m", "graphvision", "run", str(tmp_path / "p.yaml")]
    done = subprocess.run(
        [*command, "--no-cache", "--executor", "processes"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 1, done.stderr
    assert (
        "died (crashed in native code: SIGSEGV, a segmentation fault), and again when "
        "retried alone" in done.stderr
    )
    assert "Traceback" not in done.stderr.split("Fatal Python error")[0]


def test_a_worker_end_is_worded_by_its_exit_code():
    from graphvision.execution.worker_died import how_it_ended

    assert how_it_ended(-9).startswith("killed by SIGKILL")
    assert how_it_ended(-11) == "crashed in native code: SIGSEGV, a segmentation fault"
    assert how_it_ended(3).startswith("it exited with status 3")
    assert how_it_ended(None) == "killed, or out of memory"  # not known
    assert how_it_ended(-64) in ("ended by signal 64", "ended by SIGRTMAX")


def test_cache_folders_are_the_owners_only_whatever_the_umask(tmp_path):
    before = os.umask(0)
    try:
        store = gv.DiskStore.open(tmp_path / "cache")
        assert store is not None
        cache = gv.Cache(None, store)
        cache.put("ab" + "0" * 38, gv.ArrayPort, np.zeros(3))
    finally:
        os.umask(before)
    folders = [tmp_path / "cache", *(p for p in (tmp_path / "cache").iterdir() if p.is_dir())]
    assert len(folders) == 2
    for folder in folders:
        assert stat.S_IMODE(folder.stat().st_mode) == 0o700, folder
    for entry in (tmp_path / "cache").rglob("*.gvc"):
        assert stat.S_IMODE(entry.stat().st_mode) == 0o600
