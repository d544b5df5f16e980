"""An empty path is an error naming the option (an adversary's case: ``--cache-dir ''``
silently used the default cache, and ``cache clear --cache-dir ''`` emptied it); never
this folder, never the default. The same for the Python API's cache folder and an input."""

from __future__ import annotations

from pathlib import Path

import pytest

import graphvision as gv
from graphvision.cli import main

PIPELINE = """name: small
inputs:
  image: {type: Image}
nodes:
  gray: {op: colour.to_gray, in: {image: image}}
outputs: {gray: gray}
"""


@pytest.fixture
def pipeline(tmp_path: Path) -> Path:
    path = tmp_path / "small.yaml"
    path.write_text(PIPELINE)
    return path


@pytest.mark.parametrize(
    ("args", "option"),
    [
        (["run", "{p}", "--cache-dir", ""], "graphvision run: argument --cache-dir"),
        (["cache", "clear", "--cache-dir", " "], "graphvision cache: argument --cache-dir"),
        (["run", "{p}", "-d", ""], "graphvision run: argument --output-dir/-d"),
        (
            ["sweep", "{p}", "-d", "", "--grid", "x.y=1"],
            "graphvision sweep: argument --output-dir/-d",
        ),
        (["--plugins", "", "nodes"], "graphvision: argument --plugins"),
        (["report", ""], "graphvision report: argument directory"),
        (["validate", ""], "graphvision validate: argument PIPELINE"),
        (["run", ""], "graphvision run: argument pipeline"),
    ],
)
def test_an_empty_path_is_refused_naming_the_option(capsys, pipeline, args, option):
    status = main([arg.format(p=pipeline) for arg in args])
    err = capsys.readouterr().err
    assert status == 2, err
    assert err.strip() == f"error: {option}: is empty: give a path (use . for this folder)"


def test_an_empty_input_file_is_refused_naming_the_input(capsys, pipeline):
    status = main(["run", str(pipeline), "-i", "image=", "--no-cache"])
    err = capsys.readouterr().err
    assert status == 2, err
    assert err.strip() == (
        "error: input 'image': is empty: give a file, or a source such as sample:NAME"
    )


def test_an_empty_cache_folder_is_refused_from_python():
    with pytest.raises(ValueError, match="the cache folder is an empty path"):
        gv.DiskStore("")
