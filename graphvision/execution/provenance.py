"""Where a run came from: what :class:`~graphvision.RunRecord` needs to reproduce it.

:func:`describe_run` fills a record with the pipeline file and its SHA-256,
the git commit of the pipeline's folder, every used input (what was given,
a file's SHA-256, its content key), pipeline parameters and overrides,
package versions (Python, graphvision, numpy, scipy, each plugin: a
distribution's version, or a local plugin file's SHA-256), the date, and each
node's parameters and cache keys.
"""

from __future__ import annotations

import functools
import hashlib
import os
import platform
import stat
import subprocess
import sys
import weakref
from collections.abc import Collection, Mapping
from datetime import UTC, datetime
from importlib import metadata
from operator import is_
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from graphvision.compiler.compile import CompiledGraph
from graphvision.nodes.fingerprint import distributions_of
from graphvision.nodes.registry import PluginStatus, Registry
from graphvision.values.dtype_policy import dtype_name

if TYPE_CHECKING:
    from graphvision.execution.record import RunRecord

__all__ = ["describe_run", "file_sha256", "git_state", "package_versions"]

NOT_INSTALLED = "not installed"


def file_sha256(path: Path) -> str:
    """SHA-256 of a file's bytes, read in 1 MiB blocks."""
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(2**20), b""):
            digest.update(block)
    return digest.hexdigest()


_HASHED: dict[tuple[Any, ...], str] = {}
"""SHA-256 of the files and plugin folders hashed in this process, by the stamp (path, device,
inode, size, modification time in ns) of each file: a run hashes again only what changed
since (the pipeline file and each local plugin were read whole on every run)."""


def _stamp(path: str, info: os.stat_result) -> tuple[Any, ...]:
    return (path, info.st_dev, info.st_ino, info.st_size, info.st_mtime_ns)


def _known_sha256(path: str, info: os.stat_result) -> str:
    """:func:`file_sha256` of ``path`` (whose ``os.stat`` is ``info``), kept while its stamp
    is unchanged."""
    stamp = _stamp(path, info)
    known = _HASHED.get(stamp)
    if known is None:
        known = file_sha256(Path(path))
        _remember(stamp, known)
    return known


def _remember(stamp: tuple[Any, ...], digest: str) -> None:
    if len(_HASHED) > 256:
        _HASHED.clear()
    _HASHED[stamp] = digest


def _folder_sha256(folder: Path) -> str:
    """SHA-256 over the names and bytes of the ``.py`` files under ``folder`` (a plugin package),
    kept while every file's stamp is unchanged (a file added or removed changes the list)."""
    files = sorted(folder.rglob("*.py"))
    stamp = tuple(_stamp(str(path), path.stat()) for path in files)
    known = _HASHED.get(stamp)
    if known is None:
        digest = hashlib.sha256()
        for path in files:
            digest.update(str(path.relative_to(folder)).encode() + b"\0")
            digest.update(path.read_bytes())
        known = digest.hexdigest()
        _remember(stamp, known)
    return known


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
    watched = _watched(str(file.parent))
    if watched is None:  # a worktree or a submodule: ask git every time
        return _ask_git(file)
    mine = (info.st_mtime_ns, info.st_size) if info is not None else _stat(str(file))
    stamp = (file, mine, *watched)
    known = _GIT_STATES.get(stamp)
    if known is None:
        known = _ask_git(file)
        if len(_GIT_STATES) > 64:
            _GIT_STATES.clear()
        _GIT_STATES[stamp] = known
    return known


_GIT_STATES: dict[tuple[Any, ...], tuple[str, bool]] = {}


def _stat(path: str) -> tuple[int, int]:
    try:
        info = os.stat(path)
    except OSError:
        return (0, 0)
    return (info.st_mtime_ns, info.st_size)


_WATCHED: dict[str, tuple[list[str], tuple[int, int]]] = {}
"""The files :func:`_git_files` found for each folder inside a repository, with the stamp of
its ``HEAD`` then."""


def _watched(folder: str) -> list[tuple[int, int]] | None:
    """The stamps of the files of :func:`_git_files` (None: ask git every time). The walk up
    to the repository is made again only when ``HEAD``'s stamp changed (another branch,
    another ref file; ``.git`` gone), so a run makes one system call per file watched (a
    repository made since inside the one found, nearer the folder, is seen at the next
    change of the found one's ``HEAD``)."""
    known = _WATCHED.get(folder)
    if known is not None:
        stamps = [_stat(path) for path in known[0]]
        if stamps[0] == known[1]:
            return stamps
    files = _git_files(folder)
    if not files:  # outside a repository, or ``.git`` a file: walked every time
        return None if files is None else []
    stamps = [_stat(path) for path in files]
    if len(_WATCHED) > 64:
        _WATCHED.clear()
    _WATCHED[folder] = (files, stamps[0])
    return stamps


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
    stamp = _stamp(path, info)
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


@functools.cache
def _distribution_of(module: str) -> str:
    """``name version`` of the installed distribution that provides top-level ``module``."""
    names = distributions_of(module.partition(".")[0])
    for name in names:
        if (version := _version(name)) != NOT_INSTALLED:
            return f"{name} {version}"
    return ""


@functools.cache
def _version(distribution: str) -> str:
    """The installed version of ``distribution``, read once per process (each read parses
    its metadata: the 24 built-in families share one distribution)."""
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return NOT_INSTALLED


def package_versions(registry: Registry, ops: Collection[str] | None = None) -> dict[str, str]:
    """Python, graphvision, numpy, scipy and the version or file hash of each plugin that
    provides one of ``ops`` or loads input values (every loaded plugin without ``ops``).

    With ``ops`` the list depends on the pipeline alone, not on which plugins
    happened to be imported (all of them when the plugin index was missing).
    """
    versions = {
        "python": _PYTHON,
        **{name: _version(name) for name in ("graphvision", "numpy", "scipy")},
    }
    for label, origin in _plugins_listed(registry, ops):
        versions[label] = _plugin_version(origin)
    return versions


_LISTED: weakref.WeakKeyDictionary[
    Registry,
    dict[frozenset[str] | None, tuple[list[str], list[PluginStatus], list[tuple[str, str]]]],
] = weakref.WeakKeyDictionary()


def _plugins_listed(registry: Registry, ops: Collection[str] | None) -> list[tuple[str, str]]:
    """``("plugin NAME", origin)`` of each plugin :func:`package_versions` lists, in name
    order; worked out again for ``ops`` only when the registry's plugins changed (a run of
    a compiled graph asks with the same ``ops`` each time: a sort and a set intersection
    per loaded plugin were most of its provenance)."""
    names, statuses = list(registry.plugins), list(registry.plugins.values())
    known = _LISTED.setdefault(registry, {})
    found = known.get(ops) if ops is None or isinstance(ops, frozenset) else None
    if found is not None and found[0] == names and all(map(is_, found[1], statuses)):
        return found[2]
    used = set(ops) if ops is not None else None
    listed = [
        (f"plugin {name}", plugin.origin)
        for name, plugin in sorted(registry.plugins.items())
        if used is None or plugin.sources or used.intersection(plugin.nodes)
    ]
    if ops is None or isinstance(ops, frozenset):  # (a compiled graph's ops)
        if len(known) > 16:
            known.clear()
        known[ops] = (names, statuses, listed)
    return listed


_PYTHON = platform.python_version()


def _plugin_version(origin: str) -> str:
    """A local plugin file's or folder's SHA-256, else the version of the distribution of the
    module ``origin`` names (an imported module's name is no path: not looked up as one)."""
    if origin in sys.modules:
        return _imported_version(origin)
    try:
        info = os.stat(origin)
    except (OSError, ValueError):  # a module's name, not a path
        info = None
    if info is not None and stat.S_ISREG(info.st_mode):
        return f"sha256 {_known_sha256(origin, info)}"
    if info is not None and stat.S_ISDIR(info.st_mode):
        return f"sha256 {_folder_sha256(Path(origin))}"
    return _distribution_of(origin) or "unknown"


@functools.cache
def _imported_version(module: str) -> str:
    """The distribution of an imported ``module``, looked up once per process: the code
    running is the code imported, whatever is installed over it later."""
    return _distribution_of(module) or "unknown"


_RESOLVED: dict[tuple[Any, ...], Path] = {}


def _resolved(path: str, info: os.stat_result) -> Path:
    """``Path(path).resolve()`` (a system call per folder of it), kept while ``path`` (from
    the same working folder, if relative) names the same file: its device and inode."""
    where = "" if os.path.isabs(path) else os.getcwd()
    stamp = (path, where, info.st_dev, info.st_ino)
    known = _RESOLVED.get(stamp)
    if known is None:
        known = Path(path).resolve()
        if len(_RESOLVED) > 64:
            _RESOLVED.clear()
        _RESOLVED[stamp] = known
    return known


def _file_stat(path: str) -> os.stat_result | None:
    """``os.stat(path)`` if it is a file, else None."""
    try:
        info = os.stat(path)
    except (OSError, ValueError):
        return None
    return info if stat.S_ISREG(info.st_mode) else None


def _describe_input(given: Any, key: str) -> dict[str, str]:
    """What was given for an input, a file's path and SHA-256 if it is one, its content key."""
    if isinstance(given, str):
        entry = {"given": given, "key": key}
        info = _file_stat(given)
        if info is not None:
            entry |= {"path": str(Path(given).resolve()), "sha256": _known_sha256(given, info)}
        return entry
    shape = getattr(given, "shape", None)
    dtype = getattr(given, "dtype", None)
    dtype = dtype_name(dtype) if isinstance(dtype, np.dtype) else dtype
    described = f"{type(given).__name__} {shape} {dtype}" if shape is not None else repr(given)
    return {"given": described[:200], "key": key}


def describe_run(
    record: RunRecord,
    compiled: CompiledGraph,
    registry: Registry,
    given: Mapping[str, Any],
    keys: Mapping[tuple[str, str], str],
    overrides: Mapping[str, Any],
) -> None:
    """Fill ``record``'s provenance fields (each node's record holds its parameters and
    cache keys from the start)."""
    record.date = datetime.now(UTC).isoformat(timespec="seconds")
    info = _file_stat(compiled.graph.source) if compiled.graph.source else None
    if info is not None:
        source = _resolved(compiled.graph.source, info)
        record.pipeline_file = str(source)
        record.pipeline_sha256 = _known_sha256(compiled.graph.source, info)
        record.git_commit, record.git_dirty = _git_state_of(source, info)
    record.inputs = {
        name: _describe_input(value, keys.get((name, ""), "")) for name, value in given.items()
    }
    record.params = dict(compiled.graph.params)
    record.overrides = dict(overrides)
    record.versions = package_versions(registry, compiled.ops)
