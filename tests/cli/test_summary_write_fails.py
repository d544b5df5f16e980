"""A batch whose ``batch.html`` cannot be written (``ulimit -f``, a full disk) leaves no
summary half-written and exits 1, as a single run's failed write does: a tryer's batch left
a ``batch.json`` listing files that were not there, and exited 2 (a usage error). The summary
and the folders agree: the previous summary, whose rows name runs this batch replaced (kept in
their folders' ``history/``), is removed, and the folders of files no longer in the batch keep
their runs (they were retired to ``history/`` while the previous summary still listed them)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from graphvision.cli import main

PIPELINE = """name: small
inputs:
  image: {type: Image}
nodes:
  gray: {op: colour.to_gray, in: {image: image}}
  m: {op: metrics.mse, in: {a: gray, b: gray}}
outputs: {m: m}
"""

LIMITED = """import resource, sys
resource.setrlimit(resource.RLIMIT_FSIZE, (1024, 1024))  # batch.html is larger
from graphvision.cli import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.fixture
def batch(tmp_path: Path) -> tuple[Path, list[str]]:
    (tmp_path / "p.yaml").write_text(PIPELINE)
    (tmp_path / "imgs").mkdir()
    for name in "ab":
        Image.fromarray(np.full((8, 8), 100, np.uint8)).save(tmp_path / "imgs" / f"{name}.png")
    out = tmp_path / "out"
    argv = ["run", str(tmp_path / "p.yaml"), "--batch", f"image={tmp_path}/imgs/*.png"]
    return out, [*argv, "-d", str(out), "--no-cache", "--no-progress"]


def _limited(argv: list[str]) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", LIMITED, *argv], capture_output=True, text=True, timeout=120
    )


def test_a_summary_that_cannot_be_written_is_not_left_naming_replaced_runs(batch, tmp_path):
    out, argv = batch
    assert main(argv) == 0
    sizes = {name: (out / name).stat().st_size for name in ("batch.csv", "batch.html")}
    assert sizes["batch.html"] > 1024 > sizes["batch.csv"]
    (tmp_path / "imgs" / "b.png").unlink()  # b's folder: no longer in the batch
    done = _limited([*argv, "-s", "gray.method=luminance"])  # a's run is replaced
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines()[-2:] == [
        f"warning: the previous summary in {out} (batch.csv, batch.html, batch.json) is "
        "removed: its rows name runs this batch replaced (each kept in its folder's history/)",
        f"error: File too large: {out / 'batch.html'}",
    ]
    assert sorted(p.name for p in out.iterdir()) == ["a", "b"]  # no summary, no .tmp
    (kept,) = (out / "a" / "history").glob("0*")  # a's first run, which batch.csv named
    assert (kept / "record.json").is_file()
    assert sorted(p.name for p in (out / "b").iterdir()) == [  # b's run, not retired
        "m.json",
        "record.json",
        "report.html",
        "report.md",
    ]
