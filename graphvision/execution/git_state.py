"""The git state of a pipeline file for a run's provenance: the commit of its repository and
whether the file differs from it, kept while the repository's ``HEAD``, index and branch ref
are unchanged (:func:`git_state`)."""

from __future__ import annotations

import os
import stat
import subprocess
from pathlib import Path
from typing import Any

__all__ = ["file_stamp", "git_state", "git_state_stamped", "stat_stamp"]


def file_stamp(path: str, info: os.stat_result) -> tuple[Any, ...]:
    """What tells a file's versions apart: path, device, inode, size, modification time (ns)."""
    return (path, info.st_dev, info.st_ino, info.st_size, info.st_mtime_ns)


def git_state(file: Path) -> tuple[str, bool]:
    """(commit of the repository holding ``file``, whether ``file`` differs from it).

    Any failure (no git, not a repository) gives ``("", False)``. Asking git
    takes two subprocesses; the answer is kept for as long as the file and
    the repository's ``HEAD`` and index are unchanged (their sizes and
    modification times), so a batch of many runs of one pipeline asks once.
    """
    return _git_state_of(file.resolve())


def _git_state_of(file: Path, info: os.stat_result | None = None) -> tuple[str, bool]:
    """:func:`git_state` of a resolved path (``info``: its ``os.stat``, taken by the caller)."""
    return git_state_stamped(file, info)[0]


def git_state_stamped(
    file: Path, info: os.stat_result | None = None
) -> tuple[tuple[str, bool], list[str], list[tuple[int, int]]]:
    """:func:`git_state` of a resolved path (``info``: its ``os.stat``, taken by the caller),
    with the repository's files it watched (``HEAD``, the index, the branch's ref) and their
    stamps (:func:`stat_stamp`), taken before git was asked; none when git is asked every
    time (outside a repository, in a worktree or a submodule)."""
    found = _watched(str(file.parent))
    if found is None:  # a worktree or a submodule: ask git every time
        return _ask_git(file), [], []
    files, watched = found
    mine = (info.st_mtime_ns, info.st_size) if info is not None else stat_stamp(str(file))
    stamp = (file, mine, *watched)
    known = _GIT_STATES.get(stamp)
    if known is None:
        known = _ask_git(file)
        if len(_GIT_STATES) > 64:
            _GIT_STATES.clear()
        _GIT_STATES[stamp] = known
    return known, files, watched


_GIT_STATES: dict[tuple[Any, ...], tuple[str, bool]] = {}


def stat_stamp(path: str) -> tuple[int, int]:
    """A file's modification time (ns) and size; (0, 0) when it cannot be read."""
    try:
        info = os.stat(path)
    except OSError:
        return (0, 0)
    return (info.st_mtime_ns, info.st_size)


_WATCHED: dict[str, tuple[list[str], tuple[int, int]]] = {}
"""The files :func:`_git_files` found for each folder inside a repository, with the stamp of
its ``HEAD`` then."""


def _watched(folder: str) -> tuple[list[str], list[tuple[int, int]]] | None:
    """The files of :func:`_git_files` and their stamps (None: ask git every time). The walk
    up to the repository is made again only when ``HEAD``'s stamp changed (another branch,
    another ref file; ``.git`` gone), so a run makes one system call per file watched (a
    repository made since inside the one found, nearer the folder, is seen at the next
    change of the found one's ``HEAD``)."""
    known = _WATCHED.get(folder)
    if known is not None:
        stamps = [stat_stamp(path) for path in known[0]]
        if stamps[0] == known[1]:
            return known[0], stamps
    files = _git_files(folder)
    if not files:  # outside a repository, or ``.git`` a file: walked every time
        return None if files is None else ([], [])
    stamps = [stat_stamp(path) for path in files]
    if len(_WATCHED) > 64:
        _WATCHED.clear()
    _WATCHED[folder] = (files, stamps[0])
    return files, stamps


def _git_files(folder: str) -> list[str] | None:
    """``HEAD``, the checked-out branch's ref and the index of the repository above
    ``folder`` (absolute; [] outside a repository; None when ``.git`` is a file, which
    points elsewhere). One system call per folder looked at; ``HEAD`` is read again only
    when its stamp changed."""
    parent = folder
    while True:
        git_dir = os.path.join(parent, ".git")
        try:
            mode = os.stat(git_dir).st_mode
        except OSError:
            mode = 0
        if stat.S_ISDIR(mode):
            files = [os.path.join(git_dir, "HEAD"), os.path.join(git_dir, "index")]
            head = _head_of(files[0])
            if head.startswith("ref: "):
                files.append(os.path.join(git_dir, head[5:]))
            return files
        if stat.S_ISREG(mode):
            return None
        parent, child = os.path.dirname(parent), parent
        if parent == child:
            return []


_HEADS: dict[tuple[Any, ...], str] = {}


def _head_of(path: str) -> str:
    """The text of a repository's ``HEAD`` ("" when unreadable), kept while its stamp holds."""
    try:
        info = os.stat(path)
    except OSError:
        return ""
    stamp = file_stamp(path, info)
    known = _HEADS.get(stamp)
    if known is None:
        try:
            with open(path, encoding="utf-8") as handle:
                known = handle.read().strip()
        except (OSError, UnicodeDecodeError):
            return ""
        if len(_HEADS) > 64:
            _HEADS.clear()
        _HEADS[stamp] = known
    return known


def _ask_git(file: Path) -> tuple[str, bool]:
    folder = file.parent

    def git(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            ["git", "-C", str(folder), *args], capture_output=True, text=True, timeout=10
        )

    try:
        head = git("rev-parse", "HEAD")
        if head.returncode != 0:
            return "", False
        changed = git("status", "--porcelain", "--", file.name)
    except (OSError, subprocess.SubprocessError):
        return "", False
    return head.stdout.strip(), bool(changed.stdout.strip())
