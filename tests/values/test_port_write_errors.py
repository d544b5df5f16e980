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


KERNEL = "nodes:\n  k: {op: filters.gaussian_kernel, params: {sigma: SIGMA}}\noutputs: {k: k}\n"
IMAGE = (
    "inputs:\n  image: {type: Image, default: 'sample:astronaut'}\n"
    "nodes:\n  g: {op: filters.gaussian, in: {image: image}}\noutputs: {g: g}\n"
)


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_FSIZE as Linux applies it")
@pytest.mark.parametrize(
    ("nodes", "limit", "cut"),
    [
        (KERNEL.replace("SIGMA", "100"), 1024, "k.npy"),
        (IMAGE, 16, "g.png"),
        (KERNEL.replace("SIGMA", "1"), 16, "report.html"),
    ],
    ids=["npy", "png", "page"],
)
def test_a_run_whose_file_passes_the_file_size_limit_names_the_file_and_the_cause(
    tmp_path, nodes, limit, cut
):
    """A file size limit (RLIMIT_FSIZE) cuts a write short, as a full disk does: numpy's
    write said '361201 requested and 131056 written', Pillow's and the pages' a bare 'File
    too large', and the file named was in the run's hidden staging folder; each now names
    the file in the output folder (found by the tryers)."""
    pipeline = tmp_path / "big.yaml"
    pipeline.write_text(f"version: 1\nname: big\n{nodes}")
    script = textwrap.dedent(
        f"""
        import resource, sys
        resource.setrlimit(resource.RLIMIT_FSIZE, ({limit} << 10, {limit} << 10))
        from graphvision.cli import main
        sys.exit(main(["run", {str(pipeline)!r}, "-d", {str(tmp_path / "out")!r}, "--no-cache"]))
        """
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 1, done.stderr
    assert done.stderr == f"error: File too large: {tmp_path / 'out' / cut}\n", done.stderr
    assert not (tmp_path / "out").exists()  # nothing half-written is left
