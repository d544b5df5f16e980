"""``graphvision studio``: usage errors, and the server it starts (token in the URL)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

pytest.importorskip("uvicorn")

from graphvision.cli.main import main

PIPELINES = Path(__file__).parents[2] / "pipelines"


def test_a_bad_override_or_port_is_a_usage_error(capsys) -> None:
    assert main(["studio", str(PIPELINES / "coins.yaml"), "--set", "binarry.k=1",
                 "--no-browser"]) == 2  # fmt: skip
    assert "the pipeline has no node 'binarry'" in capsys.readouterr().err
    assert main(["studio", str(PIPELINES / "coins.yaml"), "--port", "70000", "--no-browser"]) == 2
    assert "--port 70000: must be between 0 and 65535" in capsys.readouterr().err


def test_a_port_in_use_is_refused_before_its_address_is_printed(capsys) -> None:
    """With ``--port N`` taken, the studio printed N's address (another server's, whose
    token it lacks), opened a browser there, then died with exit status 3."""
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        command = ["studio", str(PIPELINES / "coins.yaml"), "--port", str(port), "--no-browser"]
        assert main(command) == 2
    err = capsys.readouterr().err
    assert f"--host 127.0.0.1 --port {port}: Address already in use" in err
    assert "studio on" not in err


def test_the_command_serves_until_interrupted() -> None:
    command = [sys.executable, "-m", "graphvision", "studio", str(PIPELINES / "coins.yaml"),
               "--no-browser", "--no-cache"]  # fmt: skip
    child = subprocess.Popen(
        command, stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"},
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    try:
        assert child.stderr is not None
        line = child.stderr.readline()
        url = re.search(r"http://127\.0\.0\.1:\d+/\?token=\S+", line)
        assert url, line
        for _ in range(100):
            try:
                with urllib.request.urlopen(url.group(0), timeout=5) as page:
                    assert b"graphvision studio" in page.read()
                break
            except urllib.error.URLError:
                time.sleep(0.1)
        with pytest.raises(urllib.error.HTTPError, match="403"):
            urllib.request.urlopen(url.group(0).split("?")[0], timeout=5)
        child.send_signal(signal.SIGINT)
        assert child.wait(30) == 130
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()


def test_the_command_runs_nodes_in_its_own_processes_unless_told() -> None:
    """On threads a superseded node already running kept a core busy to its end."""
    from graphvision.cli.parser import build_parser

    parse = build_parser().parse_args
    assert parse(["studio", "p.yaml"]).executor == "processes"
    assert parse(["studio", "p.yaml", "--executor", "threads"]).executor == "threads"
    assert parse(["run", "p.yaml"]).executor == "threads"
