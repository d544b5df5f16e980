"""A command that cannot start, or is stopped, leaves nothing behind (issue 29, items E and 7).

An invalid pipeline, input, override or output makes no folder for ``run``, ``run --batch``
and ``sweep`` (exit 2); a batch whose pattern matches nothing neither. Stopped at any
moment (SIGINT: exit 130, SIGTERM: exit 143, SIGHUP: exit 129, for every command), a
command removes every folder it made, parents included, unless it holds what was finished
(a batch's finished files, a sweep's finished combinations, with their summary); a batch
always leaves its ``batch.csv``, which lists every file, done or not, even when none is
done yet.
"""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from graphvision.cli import main

from ..conftest import TOY

TOYS = """name: toys
inputs:
  image: {{type: GrayImage}}
  gain: {{type: Float{gain}}}
nodes:
  dark: {{op: toy.darken, in: {{image: image}}, params: {{factor: {factor}}}}}
  n: {{op: {count}, in: {{image: image}}}}
  g: {{op: toy.add, in: {{a: gain, b: gain}}}}
  wait: {{op: hold.wait, in: {{x: gain}}, params: {{seconds: {seconds}, marker: {marker}}}}}
outputs: {{dark: dark, n: n, g: g, wait: wait}}
"""


HOLD = """
import time
from pathlib import Path

from graphvision import Float, node


@node("hold.wait", cache=False)
def wait(x: Float, *, seconds: float = 0.0, marker: str = "") -> Float:
    '''Say that it started (a file at marker), then wait.'''
    Path(marker).write_text("started")
    time.sleep(seconds)
    return x
"""


def pipeline(tmp_path: Path, **changes: str) -> Path:
    (tmp_path / "hold.py").write_text(HOLD)
    fields = {"gain": ", default: 1.0", "factor": "0.5", "count": "toy.count", "seconds": "0.0"}
    fields["marker"] = str(tmp_path / "started")
    path = tmp_path / "toys.yaml"
    path.write_text(TOYS.format(**{**fields, **changes}))
    return path


def photos(tmp_path: Path, count: int = 2) -> Path:
    folder = tmp_path / "photos"
    for number in range(count):
        (folder / f"f{number}").mkdir(parents=True, exist_ok=True)
        iio.imwrite(
            folder / f"f{number}" / f"p{number}.png", np.full((8, 9), 30 * number, np.uint8)
        )
    iio.imwrite(tmp_path / "photo.png", np.full((8, 9), 100, np.uint8))
    return folder


def command(kind: str, tmp_path: Path, yaml: Path, out: Path) -> list[str]:
    """``run``, ``batch`` or ``sweep`` of ``yaml`` into ``out``, with the toy plugin."""
    if kind == "run":
        rest = ["run", str(yaml), "-i", f"image={tmp_path / 'photo.png'}"]
    elif kind == "batch":
        rest = ["run", str(yaml), "--batch", f"image={tmp_path}/photos/**/*.png"]
    else:
        rest = ["sweep", str(yaml), "-i", f"image={tmp_path / 'photo.png'}"]
        rest += ["--grid", "g.offset=0,1"]
    plugins = ["--plugins", str(TOY), "--plugins", str(tmp_path / "hold.py")]
    return [*plugins, *rest, "-d", str(out), "--no-cache", "--no-progress"]


INVALID = {
    "unknown op": ({"count": "toy.cont"}, [], "unknown op 'toy.cont'"),
    "parameter out of range": ({"factor": "2"}, [], "invalid value 2 for parameter 'factor'"),
    "input without value": ({"gain": ""}, [], "missing input 'gain'"),
    "bad --set": ({}, ["-s", "dark.factor=5"], "--set dark.factor=5"),
    "unknown output": ({}, ["-o", "nope"], "output 'nope'"),
    "unknown input": ({}, ["-i", "nope=1"], "input 'nope'"),
    "unreadable input": ({}, ["-i", "gain=[1"], "input 'gain'"),
}


@pytest.mark.parametrize("kind", ["run", "batch", "sweep"])
@pytest.mark.parametrize("case", sorted(INVALID))
def test_an_invalid_pipeline_or_argument_makes_no_folder(capsys, tmp_path, kind, case):
    changes, extra, message = INVALID[case]
    photos(tmp_path)
    out = tmp_path / "a" / "b" / "c"
    status = main(command(kind, tmp_path, pipeline(tmp_path, **changes), out) + extra)
    err = capsys.readouterr().err
    assert status == 2 and message in err, err
    assert not (tmp_path / "a").exists()


def test_a_batch_whose_pattern_matches_nothing_exits_2_and_makes_nothing(capsys, tmp_path):
    yaml = pipeline(tmp_path)
    out = tmp_path / "a" / "b"
    args = command("batch", tmp_path, yaml, out)
    args[args.index("--batch") + 1] = f"image={tmp_path}/none/*.png"
    assert main(args) == 2
    assert f"no file matches '{tmp_path}/none/*.png'" in capsys.readouterr().err
    assert not (tmp_path / "a").exists()


@pytest.mark.parametrize("kind", ["run", "batch", "sweep"])
@pytest.mark.parametrize(
    ("sent", "status", "word"),
    [
        ("SIGINT", 130, "interrupted"),
        ("SIGTERM", 143, "terminated"),
        # the terminal closed, an ssh connection dropped: a batch still wrote no batch.csv
        ("SIGHUP", 129, "hung up"),
    ],
)
def test_a_stopped_command_exits_with_its_signal_and_leaves_no_folder(
    tmp_path, kind, sent, status, word
):
    photos(tmp_path)
    yaml = pipeline(tmp_path, seconds="30")
    out = tmp_path / "a" / "b" / "c"
    process = subprocess.Popen(  # as a shell starts it: SIGINT delivered, whatever pytest's
        [sys.executable, "-m", "graphvision", *command(kind, tmp_path, yaml, out)],
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    for _ in range(600):  # a node runs: the run, or the first file or combination, started
        if (tmp_path / "started").exists() or process.poll() is not None:
            break
        time.sleep(0.1)
    assert (tmp_path / "started").exists()
    process.send_signal(getattr(signal, sent))
    _, err = process.communicate(timeout=60)
    assert process.returncode == status, err
    assert err.strip().splitlines()[-1].startswith(f"{word} after") and "Traceback" not in err
    if kind == "batch":  # its summary says no file is done; no file's folder is left
        rows = list(csv.DictReader((out / "batch.csv").open()))
        assert sorted(row["status"] for row in rows) == ["interrupted", "not run"]
        assert {path.name for path in out.iterdir()} == {"batch.csv", "batch.html", "batch.json"}
    else:
        assert not (tmp_path / "a").exists()


def test_a_run_stopped_while_writing_its_folder_removes_the_folders_it_made(
    capsys, tmp_path, monkeypatch
):
    import graphvision.execution.folders as folders

    written = folders.write_outputs

    def stop_after_writing(*args, **kwargs):
        written(*args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(folders, "write_outputs", stop_after_writing)
    photos(tmp_path)
    out = tmp_path / "a" / "b" / "c"
    assert main(command("run", tmp_path, pipeline(tmp_path), out)) == 130
    assert capsys.readouterr().err.startswith("interrupted after")
    assert not (tmp_path / "a").exists()


def test_a_stopped_batch_keeps_the_files_it_finished_and_no_empty_folder(
    capsys, tmp_path, monkeypatch
):
    calls = iter([None, KeyboardInterrupt])

    def interrupt_second(self, *args, **kwargs):
        if next(calls) is KeyboardInterrupt:
            raise KeyboardInterrupt

    monkeypatch.setattr("graphvision.views.progress.FileProgress.finished", interrupt_second)
    photos(tmp_path, count=3)
    out = tmp_path / "a" / "b"
    args = command("batch", tmp_path, pipeline(tmp_path), out)
    assert main([*args, "--executor", "sync"]) == 130
    assert "files done so far are listed in" in capsys.readouterr().err
    rows = list(csv.DictReader((out / "batch.csv").open()))
    assert [row["status"] for row in rows] == ["ok", "ok", "not run"]
    assert (out / "f0" / "p0" / "record.json").is_file()
    assert not (out / "f2").exists()  # made for nothing: gone
    assert all(any(folder.iterdir()) for folder in out.rglob("*") if folder.is_dir())


def _in_a_terminal(args: list[str], nohup: Path | None = None) -> tuple[subprocess.Popen, int]:
    """``graphvision ARGS`` started in a terminal of its own (a pseudo-terminal it controls,
    its output and progress written there, or as ``nohup`` starts it: SIGHUP ignored, the
    output in the file ``nohup``), and the terminal's other end."""
    import fcntl
    import pty
    import termios

    master, slave = pty.openpty()

    def session() -> None:
        os.setsid()
        fcntl.ioctl(0, termios.TIOCSCTTY, 0)
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        if nohup is not None:
            signal.signal(signal.SIGHUP, signal.SIG_IGN)

    output = slave if nohup is None else os.open(nohup, os.O_WRONLY | os.O_CREAT, 0o600)
    process = subprocess.Popen(
        [sys.executable, "-m", "graphvision", *args],
        stdin=slave,
        stdout=output,
        stderr=output,
        preexec_fn=session,
    )
    os.close(slave)
    if output != slave:
        os.close(output)
    return process, master


@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="no SIGHUP (Windows)")
@pytest.mark.parametrize("executor", ["threads", "processes"])
def test_a_batch_whose_terminal_closes_writes_batch_csv_and_exits_129(tmp_path, executor):
    """The terminal closed (an ssh connection dropped): SIGHUP, and every write to the
    terminal refused (EIO); the batch stopped as on SIGTERM, with its batch.csv, where it
    used to die at once (no batch.csv) and then, handled, fail on its message (exit 1)."""
    photos(tmp_path)
    out = tmp_path / "out"
    args = command("batch", tmp_path, pipeline(tmp_path, seconds="30"), out)
    args = [a for a in args if a != "--no-progress"] + ["--progress", "--executor", executor]
    process, terminal = _in_a_terminal(args)
    for _ in range(600):
        if (tmp_path / "started").exists() or process.poll() is not None:
            break
        time.sleep(0.1)
    assert (tmp_path / "started").exists()
    os.close(terminal)  # the terminal closes: the kernel sends SIGHUP
    assert process.wait(timeout=60) == 129
    rows = list(csv.DictReader((out / "batch.csv").open()))
    assert sorted(row["status"] for row in rows) == ["interrupted", "not run"]


@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="no SIGHUP (Windows)")
def test_a_batch_under_nohup_outlives_its_terminal(tmp_path):
    photos(tmp_path)
    out = tmp_path / "out"
    args = command("batch", tmp_path, pipeline(tmp_path, seconds="1"), out)
    process, terminal = _in_a_terminal(args, nohup=tmp_path / "nohup.out")
    for _ in range(600):
        if (tmp_path / "started").exists() or process.poll() is not None:
            break
        time.sleep(0.1)
    process.send_signal(signal.SIGHUP)
    os.close(terminal)
    assert process.wait(timeout=120) == 0, (tmp_path / "nohup.out").read_text()
    rows = list(csv.DictReader((out / "batch.csv").open()))
    assert [row["status"] for row in rows] == ["ok", "ok"]
