"""Where graphvision keeps what it caches, without importing the cache itself, and how it
opens what it keeps there."""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path
from typing import BinaryIO

__all__ = ["default_cache_dir", "not_utf8", "open_regular"]


def default_cache_dir() -> Path:
    """``$GRAPHVISION_CACHE_DIR``, else ``$XDG_CACHE_HOME/graphvision``, else ``~/.cache/...``."""
    if os.environ.get("GRAPHVISION_CACHE_DIR"):
        return Path(os.environ["GRAPHVISION_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "graphvision"


def not_utf8(path: Path) -> str | None:
    """``path`` shown with its bytes that are not UTF-8 escaped (``out\\xff``), or None
    when its name is UTF-8 (bytes that are not are held by Python as lone surrogates).
    graphvision names every file in UTF-8 (records, pages, messages): such a path is refused
    where it is given."""
    try:
        str(path).encode("utf-8")
    except UnicodeEncodeError:
        return os.fsencode(path).decode("utf-8", "backslashreplace")
    return None


def open_regular(path: str | Path) -> BinaryIO:
    """``path`` opened for reading, when it is a regular file.

    A named pipe (or a device) put where graphvision keeps a file would make a plain
    ``open`` wait for a writer, or a read never end: ``graphvision nodes`` hung on a pipe
    at its plugin index's path. The file is opened without waiting, checked, then read as
    usual.

    Raises
    ------
    OSError
        When it cannot be opened, or is not a regular file (``EINVAL``, naming it).
    """
    waitless = getattr(os, "O_NONBLOCK", 0)  # (Windows has no named pipes in folders)
    fd = os.open(path, os.O_RDONLY | waitless)
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(errno.EINVAL, "not a regular file", str(path))
        if waitless:
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise
