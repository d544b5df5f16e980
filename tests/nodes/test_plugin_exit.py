"""A plugin that calls ``os._exit`` while it is imported ends the command at once (nothing
can catch it): one line first names the plugin, where the command ended with the plugin's
status and not a word. Nothing more is written when no plugin does so."""

from __future__ import annotations

import os
import subprocess
import sys

import graphvision as gv
from graphvision.nodes.loading import exit_noted

PIPELINE = """name: p
plugins: [exits.py]
nodes:
  z: {op: pyramids.zone_plate}
outputs: {z: z}
"""


def test_a_plugin_calling_os_exit_at_import_is_named(tmp_path):
    (tmp_path / "exits.py").write_text("import os\nos._exit(3)\n")
    (tmp_path / "p.yaml").write_text(PIPELINE)
    done = subprocess.run(
        [sys.executable, "-m", "graphvision", "validate", "p.yaml"],
        cwd=tmp_path, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 3
    assert done.stderr.splitlines()[-1] == (
        f"graphvision: os._exit(3) while importing plugin {tmp_path.resolve() / 'exits.py'}"
    )


def test_os_exit_is_given_back_after_the_import(tmp_path):
    before = os._exit
    (tmp_path / "quiet.py").write_text("X = 1\n")
    gv.discover([tmp_path / "quiet.py"], entry_points=False)
    assert os._exit is before
    with exit_noted("plugin x"):
        assert os._exit is not before
    assert os._exit is before
