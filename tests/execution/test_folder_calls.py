"""Writing a batch file's folder with few system calls (each releases the GIL and takes it
again, a wait when another thread holds it): the same files and the same refusals as the
calls it replaced made."""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path

import pytest

import graphvision as gv
from graphvision.execution.folders import missing_folders, new_folder, write_run
from graphvision.execution.history import earlier_runs
from graphvision.execution.owned import write_file
from graphvision.views.report import RUN_PAGES


def _result() -> gv.RunResult:
    graph = gv.Graph("scale")
    graph.input("value", "Float")
    graph.output("value", "value")
    return gv.run(graph, inputs={"value": 2.5})


def test_write_file_makes_or_empties_the_file_as_open_wb_does(tmp_path: Path) -> None:
    write_file(tmp_path / "new.txt", b"abc\xe2\x88\x92")
    with open(tmp_path / "reference.txt", "wb") as out:
        out.write(b"x")
    assert (tmp_path / "new.txt").read_bytes() == b"abc\xe2\x88\x92"
    mode = stat.S_IMODE(os.stat(tmp_path / "new.txt").st_mode)
    assert mode == stat.S_IMODE(os.stat(tmp_path / "reference.txt").st_mode)
    (tmp_path / "old.txt").write_bytes(b"a longer content than the new one")
    os.chmod(tmp_path / "old.txt", 0o600)
    write_file(tmp_path / "old.txt", b"short")
    assert (tmp_path / "old.txt").read_bytes() == b"short"  # emptied first
    assert stat.S_IMODE(os.stat(tmp_path / "old.txt").st_mode) == 0o600  # kept


def test_missing_folders_are_those_made_deepest_first_and_a_link_is_there(
    tmp_path: Path,
) -> None:
    (tmp_path / "there").mkdir()
    (tmp_path / "broken").symlink_to(tmp_path / "nowhere")
    found = missing_folders(
        tmp_path / "a" / "b" / "c", tmp_path / "a" / "d", tmp_path / "there" / "e",
        tmp_path / "broken" / "f", tmp_path / "there",
    )  # fmt: skip
    assert set(found) == {
        tmp_path / "a" / "b" / "c",
        tmp_path / "a" / "b",
        tmp_path / "a" / "d",
        tmp_path / "broken" / "f",
        tmp_path / "there" / "e",
        tmp_path / "a",
    }
    assert len(found) == 6  # each once
    assert found[0] == tmp_path / "a" / "b" / "c" and found[-1] == tmp_path / "a"


def test_a_file_where_the_hidden_new_folder_goes_leaves_the_run_written_in_place(
    tmp_path: Path,
) -> None:
    folder = tmp_path / "out"
    new_folder(folder).write_text("not a folder")  # cannot be made there, nor removed
    assert write_run(_result(), folder, RUN_PAGES, inside=tmp_path) == {"value": ["value.json"]}
    assert json.loads((folder / "value.json").read_text()) == 2.5
    assert new_folder(folder).read_text() == "not a folder"


def test_a_folder_without_history_has_no_earlier_runs_nor_one_with_a_file_there(
    tmp_path: Path,
) -> None:
    assert earlier_runs(tmp_path) == []
    (tmp_path / "history").write_text("a file, not graphvision's folder")
    assert earlier_runs(tmp_path) == []


def test_a_batch_item_folder_that_fails_is_removed_and_the_batchs_folder_kept(
    tmp_path: Path,
) -> None:
    """The item folder is looked at once (the batch made its own folder): what a failed
    write made is removed, the batch's folder stays; a deeper folder's parents go too."""

    def failing(result: gv.RunResult, directory: Path) -> list[str]:
        raise OSError("the page cannot be written")

    batch = tmp_path / "batch"
    batch.mkdir()
    result = _result()
    for folder in (batch / "item", batch / "a" / "b" / "item"):
        with pytest.raises(OSError, match="the page cannot be written"):
            write_run(result, folder, [failing], inside=batch)
        assert list(batch.iterdir()) == []  # the item folder, its parents, its new sibling
    (batch / "item").mkdir()
    (batch / "item" / "mine.txt").write_text("a user's file")
    with pytest.raises(OSError, match="the page cannot be written"):
        write_run(result, batch / "item", [failing], inside=batch)
    assert [p.name for p in (batch / "item").iterdir()] == ["mine.txt"]  # there before
