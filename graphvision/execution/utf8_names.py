"""Paths whose names are not UTF-8: ``batch.csv``, ``record.json`` and the pages name every
file and folder in UTF-8, so such a path is refused before anything runs, shown with its
bytes that are not UTF-8 escaped (``caf\\xe9.png``)."""

from __future__ import annotations

from pathlib import Path

from graphvision.errors import InputError, OutputFolderError
from graphvision.locations import not_utf8

__all__ = ["refuse_folder_not_utf8", "refuse_names_not_utf8"]


def refuse_names_not_utf8(paths: list[Path], input: str) -> None:
    """Refuse, before anything runs, files whose names are not UTF-8: batch.csv,
    record.json and the pages, which name each file, are UTF-8, and the summary of a batch
    that ran them could not be written."""
    bad = [shown for path in paths if (shown := not_utf8(path.absolute())) is not None]
    if bad:
        raise InputError(
            f"batch input '{input}': {len(bad)} file name(s) are not UTF-8 (such as {bad[0]}): "
            "batch.csv, record.json and the pages name each file in UTF-8; rename them"
        )


def refuse_folder_not_utf8(folder: Path, option: str = "output folder") -> None:
    """Refuse, before anything runs, an output folder whose name is not UTF-8, for the
    reason of :func:`refuse_names_not_utf8` (its files could not name it: a batch ended
    with an internal error on every file), nor one in a folder whose path is not."""
    given = not_utf8(folder)
    shown = given or not_utf8(folder.absolute())
    if shown is not None:
        raise OutputFolderError(
            f"{option} {shown}: its {'name' if given else 'path'} is not UTF-8; "
            "record.json, batch.csv and the pages name it in UTF-8: choose another folder"
        )
