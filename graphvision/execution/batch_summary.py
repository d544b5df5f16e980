"""A batch's summary (``batch.csv``, ``batch.html`` and their manifest ``batch.json``) and
the folders it names: they agree, even when the summary cannot be written.

The summary is written first, whole or not at all
(:func:`~graphvision.execution.manifest.replace_folder_files`); the folders of files the
previous summary listed and this batch does not are retired to their ``history/`` only
once it is written: a summary that cannot be written (a full disk, ``ulimit -f``) retires
none of them. The files this batch ran have already replaced their folders' runs (each
previous run kept in the folder's ``history/``), so the previous summary, whose rows name
those runs, is then removed with its manifest, saying so in a warning, and the batch fails
naming the file it could not write (exit 1). When no file ran (each stopped before it
started), the previous summary still names what is there, and stays. (The previous summary
was kept whatever had run: its rows named folders this batch had emptied into ``history/``.)
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Collection
from pathlib import Path

from graphvision.errors import OutputFolderError
from graphvision.execution.batch_files import (
    BATCH_FILES,
    SUMMARY,
    SUMMARY_PAGE,
    BatchItem,
    BatchPages,
    summary_text,
)
from graphvision.execution.batch_write import settle_folders
from graphvision.execution.folders import retire_left_files
from graphvision.execution.manifest import check_folder_files, replace_folder_files

__all__ = ["summarise"]


def summarise(
    items: list[BatchItem], out_dir: Path, pages: BatchPages, stale: Collection[Path] = ()
) -> Path:
    """``batch.csv`` for ``items``, and the summary page when there is one; then the folders
    of files a previous batch listed and this one does not (``stale``) lose their files.

    Raises
    ------
    OSError
        When the summary cannot be written (:class:`~graphvision.errors.FileWriteError`,
        naming the file): nothing is retired, and the previous summary is removed when a
        file of this batch ran (see the module docstring).
    """
    settle_folders(items)  # an item without a folder says so, as batch.csv does
    contents = {SUMMARY: summary_text(items)}
    if pages.summary is not None:
        contents[SUMMARY_PAGE] = pages.summary(items, out_dir)
    try:
        replace_folder_files(out_dir, BATCH_FILES, contents)  # each whole, the manifest last
    except OSError:
        if any(item.status != "not run" for item in items):
            _remove_previous(out_dir)
        raise
    retire_left_files(stale, out_dir)  # their files are no longer in the batch
    return out_dir / SUMMARY


def _remove_previous(out_dir: Path) -> None:
    """Remove the previous summary's files from ``out_dir``, each checked as the batch's own
    (as it wrote it: else nothing is removed), its manifest last; a warning names them."""
    with contextlib.suppress(OutputFolderError, OSError):
        check_folder_files(out_dir, BATCH_FILES)
        names = [SUMMARY, SUMMARY_PAGE, BATCH_FILES.manifest]
        removed = [name for name in names if (out_dir / name).is_file()]
        for name in removed:
            (out_dir / name).unlink()
        if removed:
            warnings.warn(
                f"the previous summary in {out_dir} ({', '.join(removed)}) is removed: its "
                "rows name runs this batch replaced (each kept in its folder's history/)",
                stacklevel=4,
            )
