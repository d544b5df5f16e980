"""A batch whose ``batch.html`` cannot be written (``ulimit -f``, a full disk) changes none
of its summary files and exits 1, as a single run's failed write does: a tryer's batch left
a ``batch.json`` listing files that were not there, and exited 2 (a usage error)."""

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


def test_a_summary_that_cannot_be_written_changes_nothing_and_exits_1(batch):
    out, argv = batch
    assert main(argv) == 0
    before = {name: (out / name).read_bytes() for name in ("batch.csv", "batch.html", "batch.json")}
    assert len(before["batch.html"]) > 1024 > len(before["batch.csv"])
    done = subprocess.run(
        [sys.executable, "-c", LIMITED, *argv], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines()[-1] == f"error: File too large: {out / 'batch.html'}"
    assert {name: (out / name).read_bytes() for name in before} == before  # as they were
    assert sorted(p.name for p in out.iterdir() if p.is_file()) == sorted(before)  # no .tmp
