"""A node that kills the process on sync or threads is named by its node name (issue 29 F):
a segfault's fault-handler traceback shows the node's own frame, and ``os._exit`` writes
one line naming the nodes that were running."""

from __future__ import annotations

import subprocess
import sys

import pytest

KILLERS = '''
import ctypes
import os
from graphvision import Float, node

@node("crash.segfault")
def segfault() -> Float:
    """Reads address 8."""
    return float(ctypes.c_int.from_address(8).value)

@node("crash.exit")
def hard_exit() -> Float:
    """Ends the process at once."""
    os._exit(3)
'''


def _run(tmp_path, op: str, executor: str) -> subprocess.CompletedProcess:
    (tmp_path / "killers.py").write_text(KILLERS)
    (tmp_path / "p.yaml").write_text(
        f"version: 1\nname: killed\nplugins: [killers.py]\nnodes:\n  boom: {{op: {op}}}\n"
        "outputs:\n  value: boom\n"
    )
    command = [sys.executable, "-m", "graphvision", "run", str(tmp_path / "p.yaml")]
    return subprocess.run(
        [*command, "--no-cache", "--executor", executor],
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.mark.parametrize("executor", ["sync", "threads"])
def test_a_segfault_names_the_running_node_in_the_traceback(tmp_path, executor):
    done = _run(tmp_path, "crash.segfault", executor)
    assert done.returncode in (-11, 139)
    assert "Fatal Python error: Segmentation fault" in done.stderr
    assert "in node 'boom' (crash.segfault)" in done.stderr


@pytest.mark.parametrize("executor", ["sync", "threads"])
def test_os_exit_in_a_node_writes_one_line_naming_it(tmp_path, executor):
    done = _run(tmp_path, "crash.exit", executor)
    assert done.returncode == 3
    assert "graphvision: os._exit(3) while running node 'boom' (crash.exit)\n" in done.stderr
