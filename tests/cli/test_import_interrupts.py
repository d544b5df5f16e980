"""A Ctrl-C (SIGTERM) that comes while the command line imports a module stops it, with
its one line and its exit status: one raised inside the import system's weak-reference
callback was printed and dropped (the command went on, exit 0), one raised inside a
class's ``__set_name__`` came out wrapped in a ``RuntimeError`` (a plugin that failed to
load, or an internal error). The plugins below send the signal where Python would run its
handler inside such a callback."""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import pytest

from graphvision.cli import main

PIPELINE = """name: small
inputs:
  image: {type: Image, default: "sample:camera"}
nodes:
  gray: {op: colour.to_gray, in: {image: image}}
outputs: {gray: gray}
"""

SENDS = """import os, signal
def send():
    os.kill(os.getpid(), signal.{signal})
    [0 for _ in range(10)]  # (a call: Python runs the handler here)
"""

STOPS_HERE = {
    "weak reference": """import weakref
from .send import send
class Thing:
    pass
thing = Thing()
ref = weakref.ref(thing, lambda ref: send())
del thing  # the callback runs
""",
    "__set_name__": """from .send import send
class Field:
    def __set_name__(self, owner, name):
        send()
class Holder:
    field = Field()
""",
    "twice, the second at once": """from pathlib import Path
from .send import send
send()  # noted: the import goes on
send()  # the second one stops it
Path(__file__).with_name("went_on").touch()
""",
}
OWN_LINES = STOPS_HERE["a plugin file's own lines"] = STOPS_HERE["__set_name__"] + "\n"


def _plugin(folder: Path, signal_name: str, stops_here: str) -> Path:
    """A plugin package that imports the module ``stops_here``; or, for a plugin file's own
    lines (which the loader runs, not an import statement), that file."""
    plugin = folder / "plug"
    plugin.mkdir()
    sends = SENDS.replace("{signal}", signal_name)
    if stops_here == OWN_LINES:
        (plugin / "own.py").write_text(sends + stops_here.replace("from .send import send", ""))
        return plugin / "own.py"
    (plugin / "__init__.py").write_text("from . import stops\n")
    (plugin / "send.py").write_text(sends)
    (plugin / "stops.py").write_text(stops_here)
    return plugin


@pytest.mark.parametrize("where", list(STOPS_HERE))
@pytest.mark.parametrize(
    ("signal_name", "status", "line"),
    [("SIGINT", 130, "interrupted"), ("SIGTERM", 143, "terminated")],
)
def test_a_signal_during_an_import_stops_the_command(tmp_path, where, signal_name, status, line):
    plugin = _plugin(tmp_path, signal_name, STOPS_HERE[where])
    (tmp_path / "p.yaml").write_text(PIPELINE)
    command = [sys.executable, "-m", "graphvision", "run", str(tmp_path / "p.yaml"), "--no-cache"]
    done = subprocess.run(
        [*command, "--plugins", str(plugin), "-d", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # as a shell starts it
    )
    assert done.returncode == status, done.stderr
    assert done.stderr.startswith(f"{line} after "), done.stderr
    assert done.stderr.count("\n") == 1, done.stderr  # no "Exception ignored", no traceback
    assert not (tmp_path / "out").exists()
    assert not (plugin / "went_on").exists()


def test_a_stop_wrapped_in_another_error_is_answered_as_a_stop(monkeypatch, capsys):
    """Python wraps an exception raised in ``__set_name__`` in a RuntimeError: an internal
    error (exit 1) where it was a Ctrl-C."""

    def wrapped(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as stop:
            raise RuntimeError("Error calling __set_name__") from stop

    def in_context(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise ValueError("while handling it") from None

    monkeypatch.setattr("graphvision.cli.parser.cmd_schema", wrapped)
    assert main(["schema"]) == 130
    assert capsys.readouterr().err.startswith("interrupted after ")
    monkeypatch.setattr("graphvision.cli.parser.cmd_schema", in_context)
    assert main(["schema"]) == 130  # (in its context, though `from None` hides it)
    monkeypatch.setattr("graphvision.cli.parser.cmd_schema", lambda args: 1 / 0)
    assert main(["schema"]) == 1
    assert "internal error (ZeroDivisionError" in capsys.readouterr().err


def test_a_ctrl_c_while_python_tears_down_after_the_command_is_done_changes_nothing():
    """The command had said all and written all; a Ctrl-C in the half second Python takes
    to tear down ended it by the signal, with no word (found by NU45)."""
    script = (
        "import atexit, os, signal, sys, time\n"
        "from graphvision.cli.main import entry\n"
        "atexit.register(lambda: (os.kill(os.getpid(), signal.SIGINT), time.sleep(0.2)))\n"
        "sys.argv = ['graphvision', 'schema']\n"
        "entry()\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 0
    assert "KeyboardInterrupt" not in done.stderr and done.stdout.startswith("{")
