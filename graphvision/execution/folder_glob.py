"""A batch's glob, ``**`` searching each real folder once (:func:`glob_once`).

Python's ``glob.glob(pattern, recursive=True)`` follows symbolic links to folders
wherever ``**`` descends, and searches a folder again for every path that reaches it.
A link back up the tree (``photos/sub/up -> ..``) is searched until the paths grow too
long for the system (about 40 links deep), and with a second link aliasing a folder
(``photos/sub2 -> sub``) the paths multiply at each level: a batch over such a folder
listed hundreds of thousands of paths and gigabytes of memory before it ran a file.

A link to a folder that holds the one searched (``photos/all -> /``, ``photos/up ->
../..``) is not followed, and a warning names it: through it ``**`` would search all
of that folder (the whole file system for ``/``), far from what the pattern names.
"""

from __future__ import annotations

import glob
import heapq
import os
import warnings
from collections.abc import Iterator
from pathlib import Path

__all__ = ["glob_once"]

RECURSIVE = "**"


def glob_once(pattern: str) -> list[str]:
    """The paths ``pattern`` matches, as ``glob.glob(pattern, recursive=True)`` gives them,
    except that ``**`` searches each real folder once: by the path through the fewest
    symbolic links that reaches it (its own, where it is inside the search), then the
    shortest, then the first in name order. A folder reached again
    through a link has the files directly in it matched (so that the caller can name the
    paths a file is also reached by), and is not searched below.

    Without ``**`` a pattern descends no folder, and ``glob.glob`` answers it.
    """
    parts = pattern.split(os.sep)
    if RECURSIVE not in parts:
        return glob.glob(pattern, recursive=True)
    at = parts.index(RECURSIVE)
    prefix, rest = os.sep.join(parts[:at]), os.sep.join(parts[at + 1 :])
    tops = glob.glob(prefix) if prefix else ([os.sep] if pattern.startswith(os.sep) else [""])
    tops = sorted(t for t in tops if os.path.isdir(t or "."))
    found: list[str] = []
    around: list[str] = []  # the links to a folder holding a top, not followed
    for searched, again in _folders_once(tops, around):
        if rest:
            found.extend(_matches(searched, rest, below=not again))
        elif pattern.endswith(os.sep):  # ending in **/: the folders alone, as glob gives them
            found.extend([os.path.join(searched, "")] if searched else [])
        else:  # a pattern ending in **: the folders and their files, as glob gives them
            itself = os.path.join(searched, "") if searched in tops else searched
            inside = glob.glob(os.path.join(glob.escape(searched), "*"))
            found.extend(([itself] if itself else []) + [p for p in inside if not os.path.isdir(p)])
    if around:
        _warn_of_links_up(pattern, around)
    return found


def _warn_of_links_up(pattern: str, around: list[str]) -> None:
    """One warning naming the links ``pattern``'s ``**`` did not follow (three at most),
    each with the folder it leads to."""
    named = ", ".join(f"{link} (to {os.path.realpath(link)})" for link in around[:3])
    more = f" and {len(around) - 3} more" if len(around) > 3 else ""
    which = "a link to a folder that holds" if len(around) == 1 else "links to folders that hold"
    warnings.warn(
        f"batch '{pattern}': {named}{more} not searched: {which} the folder searched (** would "
        "search all of it)",
        stacklevel=6,  # run_batch's caller: here, glob_once, batch_files, _batch_paths, run_batch
    )


def _matches(folder: str, rest: str, *, below: bool) -> list[str]:
    """What ``rest`` matches in ``folder``; a further ``**`` in it is searched once below
    ``folder`` too (``below``), or, in a folder searched before, stands for no folder."""
    base = glob.escape(folder)
    if RECURSIVE in rest.split(os.sep) and not below:
        rest = os.sep.join(part for part in rest.split(os.sep) if part != RECURSIVE)
    return glob_once(os.path.join(base, rest)) if below else glob.glob(os.path.join(base, rest))


def _folders_once(tops: list[str], around: list[str]) -> Iterator[tuple[str, bool]]:
    """Each folder below ``tops`` (themselves included) that is not hidden, those reached
    through fewer symbolic links first, then the shallower, then in name order: every
    folder by its own path before any through a link (``photos/sub/deeper`` before
    ``photos/aa -> sub/deeper``, shorter though the link is), with whether its real folder
    was searched before (through another path): such a folder is given once (its files
    named), and not gone below. A link to a folder that holds a top is neither: it is
    added to ``around``."""
    seen: set[tuple[int, int]] = set()
    holding = _holding(tops)
    waiting = [(0, 0, top) for top in tops]  # (links, depth, folder): a heap
    heapq.heapify(waiting)
    while waiting:
        links, depth, folder = heapq.heappop(waiting)
        try:
            status = os.stat(folder or ".")
        except OSError:  # a link that loops or leads nowhere: nothing to search
            continue
        key = (status.st_dev, status.st_ino)
        if key in holding:
            around.append(folder)
            continue
        again = key in seen
        seen.add(key)
        yield folder, again
        if not again:
            for link, sub in _subfolders(folder):
                heapq.heappush(waiting, (links + link, depth + 1, sub))


def _holding(tops: list[str]) -> set[tuple[int, int]]:
    """The real folders that hold a top (its parents, up to ``/``), as (device, inode)."""
    keys = set()
    for top in tops:
        for parent in Path(os.path.realpath(top or ".")).parents:
            try:
                status = os.stat(parent)
            except OSError:
                continue
            keys.add((status.st_dev, status.st_ino))
    return keys


def _subfolders(folder: str) -> list[tuple[int, str]]:
    """The folders (or links to folders) in ``folder`` that ``**`` descends: not hidden,
    each with 1 if it is a link, else 0."""
    try:
        with os.scandir(folder or ".") as entries:
            return [
                (int(entry.is_symlink()), os.path.join(folder, entry.name))
                for entry in entries
                if not entry.name.startswith(".") and _is_dir(entry)
            ]
    except OSError:
        return []


def _is_dir(entry: os.DirEntry[str]) -> bool:
    try:
        return entry.is_dir()
    except OSError:
        return False
