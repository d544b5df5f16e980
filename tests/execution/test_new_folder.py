"""A run into a folder that does not exist yet: written whole beside its place, then renamed
into it (:func:`graphvision.execution.folders.new_folder`); the same files as a run into an
empty folder that exists, nothing hidden left beside it, whole or absent when it fails."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import graphvision as gv
from graphvision.execution.folders import clear_unfinished, new_folder, run_folder, write_run
from graphvision.execution.owned import RECORD, REPORT
from graphvision.execution.provenance import file_sha256
from graphvision.views.report import RUN_PAGES


def _result() -> gv.RunResult:
    graph = gv.Graph("scale")
    graph.input("value", "Float")
    graph.output("value", "value")
    return gv.run(graph, inputs={"value": 2.5})


def test_a_new_folder_holds_what_an_existing_empty_one_gets_and_nothing_is_left_beside_it(
    tmp_path,
):
    new, empty = tmp_path / "deep" / "new", tmp_path / "empty"
    empty.mkdir()
    assert write_run(_result(), new, RUN_PAGES, inside=tmp_path) == {"value": ["value.json"]}
    assert write_run(_result(), empty, RUN_PAGES, inside=tmp_path) == {"value": ["value.json"]}
    assert sorted(p.name for p in new.iterdir()) == sorted(p.name for p in empty.iterdir())
    assert sorted(p.name for p in new.iterdir()) == [
        "record.json",
        "report.html",
        "report.md",
        "value.json",
    ]
    assert json.loads((new / "value.json").read_text()) == 2.5
    record = json.loads((new / RECORD).read_text())
    assert record["files"] == {"value": ["value.json"]}
    assert record["file_sha256"] == {"value.json": file_sha256(new / "value.json")}
    assert sorted(p.name for p in (tmp_path / "deep").iterdir()) == ["new"]


def test_a_new_folder_left_half_written_by_a_killed_writer_is_replaced(tmp_path):
    folder = tmp_path / "out"
    left = new_folder(folder)
    left.mkdir()
    (left / "value.json").write_text("99")  # a writer killed before its record
    write_run(_result(), folder, [], inside=tmp_path)
    assert not left.exists()
    assert json.loads((folder / "value.json").read_text()) == 2.5


def test_a_page_that_fails_leaves_neither_the_new_folder_nor_its_hidden_sibling(tmp_path):
    def broken(result: gv.RunResult, directory: Path) -> list[str]:
        (directory / "page.html").write_text("half")
        raise RuntimeError("the page broke")

    folder = tmp_path / "made" / "out"
    with pytest.raises(RuntimeError, match="the page broke"):
        write_run(_result(), folder, [broken], inside=tmp_path)
    assert not (tmp_path / "made").exists()  # made for the run, removed with it


def test_a_folder_made_meanwhile_is_written_as_an_existing_one_keeping_its_files(tmp_path):
    folder = tmp_path / "out"

    def intruder(result: gv.RunResult, directory: Path) -> list[str]:
        if not folder.exists():  # someone makes the folder while the run writes beside it
            folder.mkdir()
            (folder / "notes.txt").write_text("mine")
        return []

    write_run(_result(), folder, [intruder], inside=tmp_path)
    assert sorted(p.name for p in folder.iterdir()) == ["notes.txt", "record.json", "value.json"]
    assert (folder / "notes.txt").read_text() == "mine"
    assert not new_folder(folder).exists()


def test_a_page_writing_a_new_folder_knows_the_folder_it_becomes(tmp_path):
    folder = tmp_path / "out"
    seen = []
    write_run(_result(), folder, [lambda r, d: seen.append(d) or []], inside=tmp_path)
    assert seen == [new_folder(folder)] and run_folder(seen[0]) == folder
    assert run_folder(folder / ".graphvision-writing-x1") == folder  # an existing folder's


def test_clearing_a_writer_that_died_removes_its_hidden_new_folder(tmp_path):
    folder = tmp_path / "out"
    new_folder(folder).mkdir()
    (new_folder(folder) / REPORT).write_text("half")
    clear_unfinished(folder, ["value"])
    assert not new_folder(folder).exists() and not folder.exists()


def test_a_single_runs_new_folder_is_written_in_it_never_beside_it(tmp_path):
    folder = tmp_path / "place" / "out"
    seen = []
    write_run(_result(), folder, [lambda r, d: seen.append(d) or []])
    assert seen[0].parent == folder  # nothing is written outside a run's output folder
    assert sorted(p.name for p in folder.parent.iterdir()) == ["out"]
