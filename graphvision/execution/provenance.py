"""Where a run came from: what :class:`~graphvision.RunRecord` needs to reproduce it.

:func:`describe_run` fills a record with the pipeline file and its SHA-256,
the git commit of the pipeline's folder, every used input (what was given,
a file's SHA-256, its content key), pipeline parameters and overrides,
package versions (Python, graphvision, numpy, scipy, each plugin: a
distribution's version, or a local plugin file's SHA-256), the date, and each
node's parameters and cache keys. The pipeline file is described once per compiled
graph, at its first run (:func:`_graph_file`): its later runs run the graph as it was
loaded.
"""

from __future__ import annotations

import functools
import hashlib
import os
import platform
import stat
import sys
import time
import weakref
from collections.abc import Collection, Mapping
from datetime import UTC, datetime
from importlib import metadata
from operator import is_
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from graphvision.compiler.compile import CompiledGraph
from graphvision.execution.git_state import file_stamp, git_state, git_state_stamped, stat_stamp
from graphvision.nodes.fingerprint import distributions_of
from graphvision.nodes.registry import PluginStatus, Registry
from graphvision.values.dtype_policy import dtype_name
from graphvision.values.file_bytes import read_before

if TYPE_CHECKING:
    from graphvision.execution.record import RunRecord

__all__ = ["describe_run", "file_sha256", "git_state", "package_versions"]

NOT_INSTALLED = "not installed"


def file_sha256(path: Path) -> str:
    """SHA-256 of a file's bytes, read in blocks (64 KiB, then 1 MiB): four system calls for
    a small file (open, a read, the read that finds the end, close), where a file object
    made eight (``fstat``, the ``ioctl`` asking whether it is a terminal, ``lseek``, a third
    read), each releasing the GIL and taking it back (a batch hashes each output it writes)."""
    digest = hashlib.sha256()
    descriptor = os.open(path, os.O_RDONLY | getattr(os, "O_BINARY", 0))  # (binary on Windows)
    try:
        size = 1 << 16  # (a first block that small files fill, not a MiB allocated for each)
        while block := os.read(descriptor, size):
            digest.update(block)
            size = 1 << 20
    finally:
        os.close(descriptor)
    return digest.hexdigest()


_HASHED: dict[tuple[Any, ...], str] = {}
"""SHA-256 of the files and plugin folders hashed in this process, by the stamp (path, device,
inode, size, modification time in ns) of each file: a run hashes again only what changed
since (the pipeline file and each local plugin were read whole on every run)."""


def _known_sha256(path: str, info: os.stat_result) -> str:
    """:func:`file_sha256` of ``path`` (whose ``os.stat`` is ``info``), kept while its stamp
    is unchanged."""
    stamp = file_stamp(path, info)
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
    stamp = tuple(file_stamp(str(path), path.stat()) for path in files)
    known = _HASHED.get(stamp)
    if known is None:
        digest = hashlib.sha256()
        for path in files:
            digest.update(os.fsencode(path.relative_to(folder)) + b"\0")  # (any name)
            digest.update(path.read_bytes())
        known = digest.hexdigest()
        _remember(stamp, known)
    return known


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
    listed = _plugins_listed(registry, ops)
    known = _IMPORTED_VERSIONS.get(id(listed))
    if known is not None and known[0] is listed:
        return dict(known[1])
    versions = {
        "python": _PYTHON,
        **{name: _version(name) for name in ("graphvision", "numpy", "scipy")},
    }
    for label, origin in listed:
        versions[label] = _plugin_version(origin)
    if all(origin in sys.modules for _, origin in listed):  # each read once per process
        if len(_IMPORTED_VERSIONS) > 16:
            _IMPORTED_VERSIONS.clear()
        _IMPORTED_VERSIONS[id(listed)] = (listed, versions.copy())
    return versions


_IMPORTED_VERSIONS: dict[int, tuple[list[tuple[str, str]], dict[str, str]]] = {}
""":func:`package_versions` of each list of plugins (:func:`_plugins_listed`, by identity)
whose plugins are all imported modules: each version then is read once per process
(:func:`_imported_version`, as Python's, graphvision's, NumPy's and SciPy's are), so the
answer is too. A local plugin file or folder is hashed by its stamp at every run."""


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


_PipelineFile = tuple[str, str, str, bool]
_PIPELINE_FILES: dict[
    str, tuple[tuple[Any, ...], list[str], list[tuple[int, int]], _PipelineFile]
] = {}
"""What :func:`_pipeline_file` worked out for each path, with the stamps it was worked out on."""


def _pipeline_file(path: str) -> _PipelineFile | None:
    """The pipeline file ``path`` resolved, its SHA-256 and its git state (None: no such file).

    Kept with the stamps it was decided on: the file's (device, inode, size, modification
    time; the working folder if ``path`` is relative) and its repository's ``HEAD``, index
    and branch ref's (:func:`~graphvision.execution.git_state.git_state_stamped`). A run
    compares them, one ``os.stat`` per file as before, and on any difference works each
    part out again (each checks its own stamps). Safe: each stamp is taken before the
    answer it keeps (a change meanwhile leaves it older: the next run looks again), and a
    file written or replaced between two runs has another stamp. Outside a repository or
    in a worktree (git asked every time) nothing is kept here.
    """
    info = _file_stat(path)
    if info is None:
        return None
    where = "" if os.path.isabs(path) else os.getcwd()
    stamp = (where, info.st_dev, info.st_ino, info.st_size, info.st_mtime_ns)
    known = _PIPELINE_FILES.get(path)
    if known is not None and known[0] == stamp and list(map(stat_stamp, known[1])) == known[2]:
        return known[3]
    source = _resolved(path, info)
    (commit, dirty), files, watched = git_state_stamped(source, info)
    found = (str(source), _known_sha256(path, info), commit, dirty)
    if files:
        if len(_PIPELINE_FILES) > 64:
            _PIPELINE_FILES.clear()
        _PIPELINE_FILES[path] = (stamp, files, watched, found)
    return found


_DATES: dict[int, str] = {}  # the text of the last second a date was made in


def _date_now() -> str:
    """``datetime.now(UTC).isoformat(timespec="seconds")``, made once per second."""
    second = time.time_ns() // 1_000_000_000  # (the clock datetime.now reads, floored)
    text = _DATES.get(second)
    if text is None:
        text = datetime.fromtimestamp(second, UTC).isoformat(timespec="seconds")
        _DATES.clear()
        _DATES[second] = text
    return text


def _describe_input(given: Any, key: str) -> dict[str, str]:
    """What was given for an input, a file's path and SHA-256 if it is one, its content key.

    The SHA-256 and the resolved path are those of the file as the reader read it
    (:func:`~graphvision.values.file_bytes.read_before`), when it has not changed since:
    one ``stat``, where hashing the file again and resolving its path made 13 system calls
    (each releasing the GIL and taking it back: a wait on a batch on threads)."""
    if isinstance(given, str):
        entry = {"given": given, "key": key}
        info = _file_stat(given)
        if info is not None:
            read = read_before(Path(given), info)
            path = read[1] if read is not None and read[1] else str(Path(given).resolve())
            digest = read[0] if read is not None else _known_sha256(given, info)
            entry |= {"path": path, "sha256": digest}
        return entry
    if type(given) is np.ndarray:  # (described by its shape and dtype: made once for them)
        described = _ARRAYS.get((given.shape, given.dtype))
        if described is None:
            described = _ARRAYS[(given.shape, given.dtype)] = _described(given)
            if len(_ARRAYS) > 256:
                _ARRAYS.clear()
        return {"given": described, "key": key}
    return {"given": _described(given), "key": key}


def _described(given: Any) -> str:
    shape = getattr(given, "shape", None)
    dtype = getattr(given, "dtype", None)
    dtype = dtype_name(dtype) if isinstance(dtype, np.dtype) else dtype
    described = f"{type(given).__name__} {shape} {dtype}" if shape is not None else repr(given)
    return described[:200]


_ARRAYS: dict[tuple[tuple[int, ...], np.dtype], str] = {}


def _graph_file(compiled: CompiledGraph) -> _PipelineFile | None:
    """:func:`_pipeline_file` of the compiled graph's pipeline file, as its first run found it
    (kept by the graph: :attr:`~graphvision.compiler.compiled.CompiledGraph.first_found`).

    Its later runs (a script's loop over ``gv.run(compiled, ...)``, a batch's files) run the
    graph as it was loaded, whatever happens to the file since, and record it as that first
    run did, without a system call (the four ``os.stat`` of :func:`_pipeline_file` were a
    fifth of the engine's cost on ``coins.yaml`` with the OpenCV backend, after the
    script's calls had left the kernel's caches cold). A graph loaded or compiled again
    (every command, ``gv.run`` of a path or of a ``Graph``) is looked at anew.
    """
    found = compiled.first_found
    if "file" not in found:
        source = compiled.graph.source
        found["file"] = _pipeline_file(source) if source else None
    return found["file"]


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
    record.date = _date_now()
    found = _graph_file(compiled)
    if found is not None:
        record.pipeline_file, record.pipeline_sha256, record.git_commit, record.git_dirty = found
    record.inputs = {
        name: _describe_input(value, keys.get((name, ""), "")) for name, value in given.items()
    }
    record.params = dict(compiled.graph.params)
    record.overrides = dict(overrides)
    record.versions = package_versions(registry, compiled.ops)
