"""A file graphvision cannot write is a ``FileWriteError`` (an ``OSError``, exported), named
by the file meant and not its temporary file, and nothing is left beside it."""

from __future__ import annotations

import errno
from pathlib import Path

import pytest

import graphvision as gv
from graphvision.execution.manifest import replace_bytes


def test_a_folder_in_the_place_of_a_file_is_a_file_write_error_naming_it(tmp_path: Path):
    (tmp_path / "batch.csv").mkdir()
    with pytest.raises(gv.FileWriteError) as raised:
        replace_bytes(tmp_path / "batch.csv", b"a,b\n")
    error = raised.value
    assert isinstance(error, OSError) and error.errno == errno.EISDIR
    assert error.filename == str(tmp_path / "batch.csv")
    assert str(error) == f"cannot write {tmp_path / 'batch.csv'}: Is a directory"
    assert [p.name for p in tmp_path.iterdir()] == ["batch.csv"]  # no temporary file left
