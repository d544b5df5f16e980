"""A node that forks (issue 29, item 3): the child may not run the graph. The run finishes
once, on every executor, and the child says which node it came from."""

from __future__ import annotations

import subprocess
import sys

import pytest

FORKING = '''
import os
from graphvision import Float, node

@node("forking.fork")
def fork_and_return() -> Float:
    """Forks; parent and child both return (as a library that forks carelessly would)."""
    os.fork()
    return 1.0
'''

PIPELINE = """version: 1
name: forking
plugins: [forking.py]
nodes:
  forked: {op: forking.fork}
outputs:
  value: forked
"""


@pytest.mark.parametrize("executor", ["sync", "threads", "processes"])
def test_a_forked_child_is_ended_and_the_run_finishes_once(tmp_path, executor):
    (tmp_path / "forking.py").write_text(FORKING)
    (tmp_path / "p.yaml").write_text(PIPELINE)
    command = [sys.executable, "-m", "graphvision", "run", str(tmp_path / "p.yaml")]
    command += ["--no-cache", "--executor", executor, "-d", str(tmp_path / "out")]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "node op forking.fork forked a process that returned from the node" in done.stderr
    assert done.stdout.count("value") <= 1 and done.stderr.count("wrote 1 output(s)") == 1
