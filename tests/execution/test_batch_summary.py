"""A batch's summary and the folders it names agree when the summary cannot be written
(graphvision.execution.batch_summary): nothing is retired; the previous summary goes when
a file of this batch ran (its rows name runs the batch replaced), stays when none did, and
is never removed when it is not the batch's own."""

from __future__ import annotations

import errno
from pathlib import Path

import pytest

from graphvision.errors import FileWriteError
from graphvision.execution import batch_summary
from graphvision.execution.batch_files import NO_PAGES, BatchItem
from graphvision.execution.batch_summary import summarise


def _previous(out: Path) -> tuple[Path, Path, dict[str, bytes]]:
    """A previous batch's summary of files a and b (their folders made), in ``out``."""
    for name in "ab":
        (out / name).mkdir(parents=True)
        (out / name / "record.json").write_text('{"files": {"x": ["x.json"]}}')
        (out / name / "x.json").write_text("1")
    items = [BatchItem(Path(f"in/{name}.png"), out / name) for name in "ab"]
    summarise(items, out, NO_PAGES)
    files = {name: (out / name).read_bytes() for name in ("batch.csv", "batch.json")}
    assert files["batch.csv"].decode().splitlines()[1:] == [
        f"in/a.png,{out / 'a'},ok,0.0,",
        f"in/b.png,{out / 'b'},ok,0.0,",
    ]
    return out / "a", out / "b", files


def _cannot_write(monkeypatch: pytest.MonkeyPatch) -> None:
    def refused(directory: Path, kind: object, contents: object) -> None:
        raise FileWriteError(errno.ENOSPC, "No space left on device", str(directory / "batch.csv"))

    monkeypatch.setattr(batch_summary, "replace_folder_files", refused)


def test_nothing_is_retired_and_a_summary_naming_replaced_runs_goes(tmp_path, monkeypatch):
    a, b, _ = _previous(tmp_path)
    _cannot_write(monkeypatch)
    with (
        pytest.warns(UserWarning, match=r"\(batch.csv, batch.json\) is removed: its rows name"),
        pytest.raises(FileWriteError, match="No space left"),
    ):
        summarise([BatchItem(Path("in/a.png"), a, "failed")], tmp_path, NO_PAGES, stale={b})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "b"]
    assert (b / "record.json").is_file()  # not retired: the previous summary listed it


def test_a_summary_of_a_batch_where_no_file_ran_stays(tmp_path, monkeypatch):
    _, b, files = _previous(tmp_path)
    _cannot_write(monkeypatch)
    not_run = [BatchItem(Path(f"in/{n}.png"), None, "not run") for n in "ab"]
    with pytest.raises(FileWriteError):
        summarise(not_run, tmp_path, NO_PAGES, stale={b})
    assert {name: (tmp_path / name).read_bytes() for name in files} == files
    assert (b / "record.json").is_file()


def test_a_summary_someone_edited_is_not_removed(tmp_path, monkeypatch):
    a, _, _ = _previous(tmp_path)
    with (tmp_path / "batch.csv").open("a") as summary:
        summary.write("my note\n")
    _cannot_write(monkeypatch)
    with pytest.raises(FileWriteError):
        summarise([BatchItem(Path("in/a.png"), a, "failed")], tmp_path, NO_PAGES)
    assert (tmp_path / "batch.csv").read_text().endswith("my note\n")
    assert (tmp_path / "batch.json").is_file()


def test_a_written_summary_retires_the_folders_no_longer_in_the_batch(tmp_path):
    a, b, _ = _previous(tmp_path)
    with pytest.warns(UserWarning, match=r"1 folder\(s\) of files no longer in the batch"):
        summarise([BatchItem(Path("in/a.png"), a)], tmp_path, NO_PAGES, stale={b})
    assert not (b / "record.json").exists()
    assert sorted(p.name for p in (b / "history").glob("0*/*")) == ["record.json", "x.json"]
    assert (tmp_path / "batch.csv").read_text().splitlines()[1:] == [f"in/a.png,{a},ok,0.0,"]
