"""Progress: one line per node (or a bar), long nodes announced, files with time left."""

from __future__ import annotations

import io
import re
import time
from pathlib import Path
from types import SimpleNamespace

import graphvision as gv
import graphvision.views.progress as progress_module
from graphvision.views.progress import FileProgress, RunProgress

COINS = Path(__file__).parents[2] / "pipelines" / "coins.yaml"

SLOW_PLUGIN = '''
import time
from types import SimpleNamespace
from graphvision import Float, node


@node("slow.wait")
def wait(x: Float, *, seconds: float = 0.5) -> Float:
    """Sleeps, then returns x.

    Parameters
    ----------
    x : the value
    seconds : how long to sleep
    """
    time.sleep(seconds)
    return x
'''


def test_plain_lines_count_every_computed_node() -> None:
    stream = io.StringIO()
    result = gv.run(gv.load_pipeline(COINS), hooks=[RunProgress(stream)], cache=None)
    lines = stream.getvalue().splitlines()
    total = len(result.record.nodes)
    assert lines[0] == f"running coins: {total} node(s) to compute"
    counters = [re.match(r"  \[(\d+)/(\d+)\] \w+ \([\w.]+\) computed", line) for line in lines[1:]]
    assert all(counters) and len(counters) == total
    assert [int(m.group(1)) for m in counters if m] == list(range(1, total + 1))


def test_a_long_node_is_announced_while_it_runs(tmp_path) -> None:
    plugin = tmp_path / "slow.py"
    plugin.write_text(SLOW_PLUGIN)
    graph = gv.Graph("slow")
    x = graph.input("x", "Float", default=1.0)
    graph.output("y", graph.add("y", "slow.wait", x=x, params={"seconds": 2.5}))
    stream = io.StringIO()
    gv.run(graph, gv.discover([plugin]), hooks=[RunProgress(stream, heartbeat=1.0)], cache=None)
    assert re.search(r"\.\.\. y \(slow\.wait\) still running after 1\.\d s", stream.getvalue())


def test_the_bar_reaches_the_total() -> None:
    stream = io.StringIO()
    result = gv.run(gv.load_pipeline(COINS), hooks=[RunProgress(stream, bar=True)], cache=None)
    total = len(result.record.nodes)
    assert f"{total}/{total}" in stream.getvalue()


def test_file_progress_reports_failures_and_time_left() -> None:
    stream = io.StringIO()
    progress = FileProgress(3, stream=stream, bar=False)
    for name, ok in [("a.png", True), ("b.png", False), ("c.png", True)]:
        time.sleep(0.01)
        progress.finished(name, ok, 0.01)
    progress.close()
    lines = stream.getvalue().splitlines()
    assert lines[1].startswith("  [2/3 files] b.png FAILED")
    assert all("left)" in line for line in lines)
    assert lines[-1].endswith("(about 0 ms left)")


def test_time_left_counts_from_when_the_work_began():
    """A batch makes its progress when the first file is done (the total is known
    then): the estimate must still count that file's time."""
    stream = io.StringIO()
    progress = FileProgress(4, stream=stream, bar=False, began=time.monotonic() - 2.0)
    progress.finished("a.png", True, 2.0)
    left = stream.getvalue().split("(about ")[1]
    assert left.startswith(("5.", "6.")) and left.endswith(" s left)\n")  # 3 files × 2 s


def test_time_left_leaves_out_the_first_files_start_up(monkeypatch):
    """Start-up of 9 s, then a file a second: after 5 files, 95 are left at 1 s each. The
    pace since the work began (14 s for 5 files) would say 266 s."""
    clock = iter([10.0, 11.0, 12.0, 13.0, 14.0])
    monkeypatch.setattr(progress_module, "time", SimpleNamespace(monotonic=lambda: next(clock)))
    stream = io.StringIO()
    progress = FileProgress(100, stream=stream, bar=False, began=0.0)
    for name in "abcde":
        progress.finished(f"{name}.png", True, 1.0)
    lines = stream.getvalue().splitlines()
    assert lines[0].endswith("(about 16 min 30 s left)")  # from the start: 10 s a file
    assert lines[-1].endswith("(about 95.0 s left)"), lines[-1]
