"""One writer at a time per output folder (an adversary's case: two batches into one folder).

While a process holds a folder's writer lock, ``run -d``, ``run --batch`` and ``sweep`` into
that folder are refused (exit 2) naming the process and what it is doing, before anything
runs and without touching the folder; a holder killed with ``kill -9`` holds nothing, and
the next writer takes its left-over lock file over and removes it when it ends.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from graphvision.cli import main
from graphvision.errors import OutputFolderError
from graphvision.execution.folder_lock import LOCK_FILE, only_writer

PIPELINE = """name: halve
inputs:
  image: {type: Image, default: "sample:camera"}
nodes:
  gray: {op: colour.to_gray, in: {image: image}}
outputs: {gray: gray}
"""

HOLDER = """
import sys, time
from pathlib import Path
from graphvision.execution.folder_lock import only_writer
with only_writer(Path(sys.argv[1]), "batch of photos"):
    print("held", flush=True)
    time.sleep(120)
"""


@pytest.fixture
def pipeline(tmp_path: Path) -> Path:
    path = tmp_path / "halve.yaml"
    path.write_text(PIPELINE)
    return path


def _hold(folder: Path) -> subprocess.Popen[str]:
    """A process holding ``folder``'s lock until killed."""
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLDER, str(folder)], stdout=subprocess.PIPE, text=True
    )
    assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
    return holder


def _listing(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def test_every_writing_command_is_refused_while_another_process_writes(capsys, tmp_path, pipeline):
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    images = tmp_path / "images"
    images.mkdir()
    iio.imwrite(images / "a.png", np.zeros((8, 8), np.uint8))
    holder = _hold(out)
    try:
        before = _listing(out)
        commands = (
            ["run", str(pipeline), "-d", str(out)],
            ["run", str(pipeline), "-d", str(out), "--batch", f"image={images}/*.png"],
            ["sweep", str(pipeline), "-d", str(out), "--grid", "gray.method=mean,luminance"],
        )
        for command in commands:
            assert main(command) == 2, command
            err = capsys.readouterr().err
            assert (
                f"error: output folder {out} is being written by process {holder.pid} "
                "(batch of photos)" in err
            ), err
            assert "choose another --output-dir" in err
            assert _listing(out) == before  # nothing written, nothing removed
    finally:
        holder.kill()
        holder.wait()


def test_a_writer_killed_with_kill_9_holds_nothing(capsys, tmp_path, pipeline):
    out = tmp_path / "out"
    holder = _hold(out)
    os.kill(holder.pid, signal.SIGKILL)
    holder.wait()
    assert (out / LOCK_FILE).is_file()  # left behind, as a kill leaves it
    assert main(["run", str(pipeline), "-d", str(out)]) == 0, capsys.readouterr().err
    assert (out / "gray.png").is_file()
    assert not (out / LOCK_FILE).exists()  # taken over, then removed


def test_a_second_lock_in_the_same_process_is_refused(tmp_path):
    refused = pytest.raises(OutputFolderError, match=rf"process {os.getpid()} \(run of a\)")
    with only_writer(tmp_path, "run of a"), refused, only_writer(tmp_path, "run of b"):
        pass  # pragma: no cover - never entered
    assert not (tmp_path / LOCK_FILE).exists()
    with only_writer(tmp_path):  # free again
        assert (tmp_path / LOCK_FILE).is_file()


def test_a_link_named_as_the_lock_is_refused_and_its_target_untouched(capsys, tmp_path, pipeline):
    out = tmp_path / "out"
    out.mkdir()
    target = tmp_path / "precious.txt"
    target.write_text("keep")
    (out / LOCK_FILE).symlink_to(target)
    assert main(["run", str(pipeline), "-d", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"output folder {out} holds {LOCK_FILE}, which is not graphvision's lock file" in err
    assert target.read_text() == "keep"
    assert (out / LOCK_FILE).is_symlink()


@pytest.mark.parametrize("kind", ["hard link", "pipe"])
def test_a_hard_link_or_a_pipe_named_as_the_lock_is_refused_and_left_alone(
    capsys, tmp_path, pipeline, kind
):
    out = tmp_path / "out"
    out.mkdir()
    precious = tmp_path / "precious.txt"
    precious.write_text("keep")
    if kind == "hard link":  # another name of the user's file: writing to it would change it
        os.link(precious, out / LOCK_FILE)
        why = "another name of a file"
    else:
        os.mkfifo(out / LOCK_FILE)
        why = "not a file"
    assert main(["run", str(pipeline), "-d", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"holds {LOCK_FILE}, which is not graphvision's lock file ({why}): remove it" in err
    assert precious.read_text() == "keep"
    assert os.path.lexists(out / LOCK_FILE)  # not removed either
    assert sorted(p.name for p in out.iterdir()) == [LOCK_FILE]  # and nothing written


def test_a_folder_that_cannot_be_written_is_said_so(capsys, tmp_path, pipeline, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    real_open = os.open

    def refused(path, flags, mode=0o777, **kwargs):  # as a read-only mount refuses
        if str(path).endswith(LOCK_FILE):
            raise PermissionError(13, "Permission denied", str(path))
        return real_open(path, flags, mode, **kwargs)

    monkeypatch.setattr(os, "open", refused)
    assert main(["run", str(pipeline), "-d", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"error: output folder {out} cannot be written (Permission denied)" in err
    assert list(out.iterdir()) == []


def test_a_full_disk_is_said_so_naming_the_folder(capsys, tmp_path, pipeline, monkeypatch):
    """The lock's one line is the first thing written: a full disk refused it with a bare
    "No space left on device" and no path."""
    import errno

    out = tmp_path / "a" / "out"

    def full(*args):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "pwrite", full)
    assert main(["run", str(pipeline), "-d", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"error: {out}: cannot write its lock file {LOCK_FILE} (No space left on device)" in err
    assert not (tmp_path / "a").exists()  # made for the run, removed again


def test_a_file_of_the_users_named_as_the_lock_is_refused_and_kept(capsys, tmp_path, pipeline):
    out = tmp_path / "out"
    out.mkdir()
    (out / LOCK_FILE).write_text("my notes\n")
    assert main(["run", str(pipeline), "-d", str(out)]) == 2
    err = capsys.readouterr().err
    why = "(it holds something else)"
    assert f"holds {LOCK_FILE}, which is not graphvision's lock file {why}" in err
    assert (out / LOCK_FILE).read_text() == "my notes\n"
