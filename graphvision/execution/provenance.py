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
import platform
import subprocess
from collections.abc import Collection, Mapping
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

from graphvision.compiler.compile import CompiledGraph
from graphvision.nodes.fingerprint import distributions_of
from graphvision.nodes.registry import Registry

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


def _folder_sha256(folder: Path) -> str:
    """SHA-256 over the names and bytes of the ``.py`` files under ``folder`` (a plugin package)."""
    digest = hashlib.sha256()
    for path in sorted(folder.rglob("*.py")):
        digest.update(str(path.relative_to(folder)).encode() + b"\0")
        digest.update(path.read_bytes())
    return digest.hexdigest()


def git_state(file: Path) -> tuple[str, bool]:
    """(commit of the repository holding ``file``, whether ``file`` differs from it).

    Any failure (no git, not a repository) gives ``("", False)``. Asking git
    takes two subprocesses; the answer is kept for as long as the file and
    the repository's ``HEAD`` and index are unchanged (their sizes and
    modification times), so a batch of many runs of one pipeline asks once.
    """
    file = file.resolve()
    watched = _git_files(file.parent)
    if watched is None:  # a worktree or a submodule: ask git every time
        return _ask_git(file)
    stamp = (file, _stat(file), *(_stat(p) for p in watched))
    known = _GIT_STATES.get(stamp)
    if known is None:
        known = _ask_git(file)
        if len(_GIT_STATES) > 64:
            _GIT_STATES.clear()
        _GIT_STATES[stamp] = known
    return known


_GIT_STATES: dict[tuple[Any, ...], tuple[str, bool]] = {}


def _stat(path: Path) -> tuple[int, int]:
    try:
        info = path.stat()
    except OSError:
        return (0, 0)
    return (info.st_mtime_ns, info.st_size)


def _git_files(folder: Path) -> list[Path] | None:
    """``HEAD``, the checked-out branch's ref and the index of the repository above
    ``folder`` ([] outside a repository; None when ``.git`` is a file, which points
    elsewhere)."""
    for parent in (folder, *folder.parents):
        git_dir = parent / ".git"
        if git_dir.is_dir():
            files = [git_dir / "HEAD", git_dir / "index"]
            try:
                head = (git_dir / "HEAD").read_text().strip()
            except OSError:
                return files
            if head.startswith("ref: "):
                files.append(git_dir / head[5:])
            return files
        if git_dir.is_file():
            return None
    return []


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
        "python": platform.python_version(),
        **{name: _version(name) for name in ("graphvision", "numpy", "scipy")},
    }
    used = set(ops) if ops is not None else None
    for name, plugin in sorted(registry.plugins.items()):
        if used is not None and not (plugin.sources or used.intersection(plugin.nodes)):
            continue
        origin = Path(plugin.origin)
        if origin.is_file():
            versions[f"plugin {name}"] = f"sha256 {file_sha256(origin)}"
        elif origin.is_dir():
            versions[f"plugin {name}"] = f"sha256 {_folder_sha256(origin)}"
        else:
            versions[f"plugin {name}"] = _distribution_of(plugin.origin) or "unknown"
    return versions


def _describe_input(given: Any, key: str) -> dict[str, str]:
    """What was given for an input, a file's path and SHA-256 if it is one, its content key."""
    if isinstance(given, str):
        entry = {"given": given, "key": key}
        path = Path(given)
        if path.is_file():
            entry |= {"path": str(path.resolve()), "sha256": file_sha256(path)}
        return entry
    shape = getattr(given, "shape", None)
    dtype = getattr(given, "dtype", None)
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
    source = Path(compiled.graph.source) if compiled.graph.source else None
    if source is not None and source.is_file():
        record.pipeline_file = str(source.resolve())
        record.pipeline_sha256 = file_sha256(source)
        record.git_commit, record.git_dirty = git_state(source)
    record.inputs = {
        name: _describe_input(value, keys.get((name, ""), "")) for name, value in given.items()
    }
    record.params = dict(compiled.graph.params)
    record.overrides = dict(overrides)
    record.versions = package_versions(registry, {s.spec.id for s in compiled.steps.values()})
