"""An output folder keeps its earlier runs: a warm re-run no longer replaces the cold run's
report, and --keep-intermediates shows the values of cached nodes too."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from graphvision.cli import main
from graphvision.execution import history

PIPELINES = Path(__file__).parents[2] / "pipelines"


def _run(folder: Path, cache: Path, *extra: str) -> None:
    command = ["run", str(PIPELINES / "line_fit.yaml"), "-d", str(folder)]
    assert main([*command, "--cache-dir", str(cache), "--executor", "sync", *extra]) == 0


def _statuses(record: Path) -> set[str]:
    return {node["status"] for node in json.loads(record.read_text())["nodes"]}


def test_a_warm_rerun_keeps_the_cold_runs_report_and_files(tmp_path):
    folder, cache = tmp_path / "out", tmp_path / "cache"
    _run(folder, cache)
    cold = (folder / "report.html").read_text()
    _run(folder, cache)
    assert _statuses(folder / "record.json") - {"unneeded"} == {"cached"}
    (entry,) = [p for p in (folder / "history").iterdir() if p.is_dir()]
    assert (entry / "report.html").read_text() == cold  # the cold run's page, as it was
    assert _statuses(entry / "record.json") == {"computed"}
    kept = json.loads((entry / "record.json").read_text())["files"]
    assert all((entry / name).is_file() for names in kept.values() for name in names)
    page = (folder / "report.html").read_text()
    assert f'href="./history/{entry.name}/report.html"' in page
    assert "Earlier runs (newest first)" in page and "Earlier runs" not in cold
    assert f"](history/{entry.name}/report.md): 7 computed" in (folder / "report.md").read_text()


def test_history_is_newest_first_and_bounded(tmp_path, monkeypatch):
    monkeypatch.setattr(history, "KEPT_RUNS", 2)
    folder, cache = tmp_path / "out", tmp_path / "cache"
    for threshold in (1.0, 2.0, 3.0, 4.0):
        _run(folder, cache, "--set", f"robust.threshold={threshold}")
    runs = history.earlier_runs(folder)
    assert [run.record["overrides"]["robust.threshold"] for run in runs] == [3.0, 2.0]
    page = (folder / "report.html").read_text()
    linked = re.findall(r'href="\./(history/[^"]+)/report\.html"', page)
    assert linked == [run.folder for run in runs]


@pytest.mark.parametrize("warm", [False, True])
def test_keep_intermediates_shows_cached_nodes_too(tmp_path, warm):
    folder, cache = tmp_path / "out", tmp_path / "cache"
    if warm:
        _run(tmp_path / "first", cache)  # every node cached
    _run(folder, cache, "--keep-intermediates")
    if warm:
        assert _statuses(folder / "record.json") == {"cached"}
    page = (folder / "report.html").read_text()
    headings = re.findall(r"<h3>([^<]+)</h3>", page.split("Intermediate values")[-1])
    assert {"lstsq", "total", "points.truth"} <= set(headings)


@pytest.mark.parametrize("planted", ["symlink", "file"])
def test_a_planted_staging_name_neither_blocks_the_next_run_nor_is_written_through(
    tmp_path, planted
):
    """The staging folder's name follows from record.json; a symlink or a file planted there
    made every later run fail with 'File exists' until someone removed it."""
    import hashlib

    folder, cache, victim = tmp_path / "out", tmp_path / "cache", tmp_path / "victim"
    victim.mkdir()
    _run(folder, cache)
    raw = (folder / "record.json").read_bytes()
    date = str(json.loads(raw)["date"]).replace("+00:00", "Z")
    name = f"000001-{re.sub(r'[^0-9TZ.]', '', date)}-{hashlib.sha256(raw).hexdigest()[:8]}"
    (folder / "history").mkdir()
    (folder / "history" / history.MARKER).touch()
    staging = folder / "history" / f".{name}.writing"
    if planted == "symlink":
        staging.symlink_to(victim, target_is_directory=True)
    else:
        staging.write_text("planted")
    _run(folder, cache)
    assert (folder / "history" / name / "record.json").read_bytes() == raw
    assert list(victim.iterdir()) == []


def test_rewrite_report_takes_the_folder_as_a_string_too(tmp_path):
    """``gv.rewrite_report("out/r")``, as a user types it (it raised TypeError on ``/``)."""
    import graphvision as gv

    folder = tmp_path / "out"
    _run(folder, tmp_path / "cache")
    before = (folder / "report.md").read_text()
    (folder / "report.md").unlink()
    assert gv.rewrite_report(str(folder)) == folder / "report.html"
    assert (folder / "report.md").read_text() == before
