"""An output that cannot be written whole names its file and the cause: numpy reports a
write C cut short as ``OSError('116352 requested and 39904 written')`` (no errno, no file),
which the command line printed as it was."""

from __future__ import annotations

import errno
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from graphvision.values.ports import ArrayPort

FULL = Path("/dev/full")  # every write to it fails: "No space left on device"


@pytest.mark.skipif(not FULL.exists(), reason="needs /dev/full")
def test_a_short_write_is_made_again_to_say_why(tmp_path, monkeypatch):
    """numpy's short count (a disk that filled during the write) becomes the cause."""
    (tmp_path / "k.npy").symlink_to(FULL)
    saved = np.save

    def cut_short(path, array, allow_pickle):  # as numpy reports a short fwrite
        saved(tmp_path / "elsewhere.npy", array, allow_pickle=allow_pickle)
        raise OSError("116352 requested and 39904 written")

    monkeypatch.setattr(np, "save", cut_short)
    with pytest.raises(OSError) as caught:
        ArrayPort.write(np.zeros((120, 121)), tmp_path / "k")
    assert caught.value.errno == errno.ENOSPC
    assert str(caught.value) == f"[Errno 28] No space left on device: '{tmp_path / 'k.npy'}'"


def test_a_write_cut_short_then_possible_is_written_whole(tmp_path, monkeypatch):
    saved, array = np.save, np.arange(300.0).reshape(15, 20)
    monkeypatch.setattr(np, "save", lambda *a, **k: (_ for _ in ()).throw(OSError("1 requested")))
    (path,) = ArrayPort.write(array, tmp_path / "k")
    monkeypatch.setattr(np, "save", saved)
    saved(tmp_path / "reference.npy", array, allow_pickle=False)
    assert path.read_bytes() == (tmp_path / "reference.npy").read_bytes()  # np.save's bytes


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_FSIZE as Linux applies it")
def test_a_run_whose_output_passes_the_file_size_limit_names_the_file_and_the_cause(tmp_path):
    """A file size limit (RLIMIT_FSIZE) cuts np.save's write short, as a full disk does."""
    pipeline = tmp_path / "big.yaml"
    pipeline.write_text(
        "version: 1\nname: big\nnodes:\n"
        "  k: {op: filters.gaussian_kernel, params: {sigma: 100}}\noutputs: {k: k}\n"
    )  # a 601 x 601 float64 kernel: 2.9 MB, written as k.npy
    script = textwrap.dedent(
        f"""
        import resource, sys
        resource.setrlimit(resource.RLIMIT_FSIZE, (1 << 20, 1 << 20))
        from graphvision.cli import main
        sys.exit(main(["run", {str(pipeline)!r}, "-d", {str(tmp_path / "out")!r}, "--no-cache"]))
        """
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 1, done.stderr
    assert done.stderr.startswith(f"error: File too large: {tmp_path / 'out'}/"), done.stderr
    assert done.stderr.rstrip().endswith("/k.npy") and "requested" not in done.stderr
    assert not (tmp_path / "out").exists()  # nothing half-written is left
