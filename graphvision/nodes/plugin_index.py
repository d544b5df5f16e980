"""The plugin index: what discovering the installed plugins found, kept on disk.

Importing every installed family and building each node's parameter model
(a pydantic model, checked on the defaults, and its JSON schema) is most of
what ``graphvision nodes`` and the start of a run cost. The index records,
for one state of the installed plugins, each node's listing line and
description, and that every node registered. With an index that matches,

* ``graphvision nodes`` and ``graphvision describe`` print from it without
  importing any plugin (nor NumPy, nor pydantic);
* :func:`~graphvision.discover` still imports the plugins (a run calls their
  functions) but leaves each parameter model to be built on first use, so a
  run builds the models of the nodes it uses only.

An index is never served stale: it is keyed by a digest of everything that
can change what discovery finds, computed on every use:

* the bytes of every file of each entry point's top-level package and of
  graphvision itself (an edit anywhere in a plugin shows at once, whatever
  the file's time stamp; a process hashes a file again only when its status,
  ``ctime`` included, changed: :func:`_file_digest`);
* the entry points (name, target, and their distribution's metadata file,
  which holds its name and version);
* the modification time of each ``sys.path`` folder but the first, each once (a package
  installed or removed there, such as a dependency a plugin imports; the
  first is the script's folder or, for ``python -m``, the current one, whose
  time changes with every file made there, and the packages it provides are
  hashed as above);
* the Python version and executable.

The other top-level modules a plugin's import brought in from its distribution
(its nodes defined in a second package of the distribution) are not known
before the import: the index records their digests, and is not served when one
changed.

An index is written only after a discovery in which every entry-point plugin
loaded (a failing plugin is imported, and its error reported, every time),
only if the key is the same after the plugins were imported as before (a
file edited meanwhile), and only if no file of the plugins' modules changed
after they could have been imported (:mod:`graphvision.nodes.plugin_modules`:
a module imported before its file was edited holds the old nodes). It is one
JSON file per Python environment, next to the default cache folder, named by
its key and written atomically; an index that cannot be read or written is
simply not used.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import sys
import tempfile
import time
from importlib.metadata import EntryPoint, entry_points
from importlib.util import find_spec
from pathlib import Path
from typing import TYPE_CHECKING, Any

from graphvision.locations import default_cache_dir, open_regular
from graphvision.nodes.index_shape import INDEX, fits

if TYPE_CHECKING:
    from graphvision.nodes.registry import Registry

__all__ = [
    "ENTRY_POINT_GROUP",
    "environment_key",
    "has_index",
    "index_path",
    "installed_entry_points",
    "metadata_folder",
    "package_digest",
    "package_files",
    "read_index",
    "read_providers",
    "write_index",
]

ENTRY_POINT_GROUP = "graphvision.plugins"
FORMAT = 6  # bump when what an index holds changes


def installed_entry_points() -> list[EntryPoint]:
    """The ``graphvision.plugins`` entry points, in name order.

    Listing them reads every installed distribution's metadata (4 ms here); a process
    lists them again only when a ``sys.path`` folder changed (installing or removing a
    distribution adds or removes its metadata folder there) or the ``entry_points.txt`` of
    a distribution listed (edited in place), or when one had changed in the two seconds
    before the last listing (see :func:`_file_digest`).
    """
    stamp = _stamp(sys.path)
    if stamp is not None and _ENTRY_POINTS and _ENTRY_POINTS[0] == stamp:
        files = _ENTRY_POINTS[1]
        if _stamp(files) == _ENTRY_POINTS[2]:
            return list(_ENTRY_POINTS[3])
    found = sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name)
    folders = {metadata_folder(e.dist) for e in found}
    files = sorted(os.path.join(folder, "entry_points.txt") for folder in folders if folder)
    listed = _stamp(files)
    settled = stamp is not None and listed is not None
    _ENTRY_POINTS[:] = [stamp, files, listed, tuple(found)] if settled else []
    return found


# [the sys.path folders' stamp, the entry_points.txt files read, their stamp, what they list]
_ENTRY_POINTS: list = []


def metadata_folder(dist: Any) -> Any:
    """The folder of a distribution's metadata (``*.dist-info``), or None: it names one
    distribution where each entry point brings its own distribution object."""
    return getattr(dist, "_path", None)  # (PathDistribution's; others have none)


_SETTLED_NS = 2_000_000_000  # a status older than this is kept (see _file_digest)


def _settled(status: os.stat_result) -> bool:
    """Whether a file last changed over two seconds ago: the clock that stamps files is
    coarse, so a status kept from a more recent change may not tell the next one."""
    return time.time_ns() - max(status.st_mtime_ns, status.st_ctime_ns) > _SETTLED_NS


def _stamp(paths: list[str]) -> tuple | None:
    """Each path's status, or None when one changed in the last two seconds."""
    stamp: list[tuple[str, int | None, int, int]] = []
    for path in paths:
        try:
            status = os.stat(path or ".")
        except OSError:
            stamp.append((path, None, 0, 0))
            continue
        if not _settled(status):
            return None
        stamp.append((path, status.st_ino, status.st_mtime_ns, status.st_ctime_ns))
    return tuple(stamp)


def environment_key(entries: list[EntryPoint]) -> str:
    """A digest of what discovering ``entries`` depends on (see the module docstring).

    xxh3-128, as the cache's content keys: a megabyte of plugin sources is
    hashed in well under a millisecond.
    """
    import xxhash

    hasher = xxhash.xxh3_128()
    # The interpreter's path normalised: one interpreter started as .venv/bin/python and as
    # bench/../.venv/bin/python is one environment, with one index.
    interpreter = os.path.abspath(sys.executable)  # abspath normalises "a/../b" too
    hasher.update(f"{FORMAT}|{sys.version}|{interpreter}\n".encode())
    for folder in _path_folders():
        with contextlib.suppress(OSError):
            hasher.update(f"{folder}|{os.stat(folder or '.').st_mtime_ns}\n".encode())
    packages = {"graphvision"}
    releases: dict[object, str] = {}  # read once per distribution (parsing it is slow)
    for entry in entries:
        dist = entry.dist
        where = metadata_folder(dist) or id(dist)
        if dist is not None and where not in releases:
            releases[where] = dist.read_text("METADATA") or dist.read_text("PKG-INFO") or ""
        release = releases[where] if dist is not None else ""
        hasher.update(f"{entry.name}|{entry.value}|{release}\n".encode())
        packages.add(entry.value.partition(":")[0].partition(".")[0])
    for package in sorted(packages):
        hasher.update(f"package {package}\n".encode())
        hasher.update(package_digest(package))
    return hasher.hexdigest()


# A file's digest, kept with the status that stamped it: (inode, size, mtime, ctime).
_DIGESTS: dict[str, tuple[tuple[int, int, int, int], bytes]] = {}


def _file_digest(name: str) -> bytes:
    """The xxh3-128 digest of file ``name``'s bytes (empty when it cannot be read), hashed again
    only when its status changed.

    Every write sets a file's ``ctime`` (no tool can set it back, unlike ``mtime``), so a
    file whose inode, size, ``mtime`` and ``ctime`` are those of its last hashing holds the
    same bytes. The clock that stamps them is coarse (milliseconds), so two writes close
    together can leave the same status: a digest is kept only for a file last changed
    over two seconds before it was hashed (git's "racy clean" rule), and a recent file is
    read every time. The first discovery of a process reads every file; those after it
    (a batch, a sweep, each ``gv.run`` of a graph) stat them: 10 ms a discovery became 1.
    """
    import xxhash

    try:
        status = os.stat(name)
    except OSError:
        return b""
    stamp = (status.st_ino, status.st_size, status.st_mtime_ns, status.st_ctime_ns)
    kept = _DIGESTS.get(name)
    if kept is not None and kept[0] == stamp:
        return kept[1]
    try:
        with open(name, "rb") as stream:
            digest = xxhash.xxh3_128_digest(stream.read())
    except OSError:
        return b""
    if _settled(status):
        _DIGESTS[name] = (stamp, digest)
    return digest


def package_digest(name: str) -> bytes:
    """A digest of the files of the top-level package or module ``name`` (names and bytes)."""
    import xxhash

    hasher = xxhash.xxh3_128()
    for file in package_files(name):
        hasher.update(os.fsencode(file) + b"\n")  # (a name not UTF-8 too)
        hasher.update(_file_digest(file))
    return hasher.digest()


def _path_folders() -> list[str]:
    """``sys.path`` but its first folder, each folder once: a worker process started by
    multiprocessing has its script's folder on its path twice (its own first entry, then
    the client's path after it), and must find the client's index all the same."""
    first = sys.path[0] if sys.path else None
    return list(dict.fromkeys(folder for folder in sys.path[1:] if folder != first))


def package_files(name: str) -> list[str]:
    """Every file of a top-level package or module, found without importing it (but for
    ``__pycache__``)."""
    try:
        spec = find_spec(name)
    except (ImportError, ValueError):
        return []
    if spec is None:
        return []
    if not spec.submodule_search_locations:
        return [str(Path(spec.origin))] if spec.origin else []
    files = []
    for location in spec.submodule_search_locations:
        for folder, subfolders, names in os.walk(str(Path(location))):
            subfolders[:] = sorted(d for d in subfolders if d != "__pycache__")
            files += [os.path.join(folder, n) for n in sorted(names) if not n.endswith(".pyc")]
    return files


def index_path(key: str) -> Path:
    """The index file of ``key`` in this Python environment, beside the default cache folder.

    The key is in the name, so a discovery knows whether the index matches
    from the file's existence alone, without reading it.
    """
    return _index_stem().with_name(f"{_index_stem().name}{key}.json")


def _index_stem() -> Path:
    environment = hashlib.blake2b(sys.prefix.encode(), digest_size=4).hexdigest()
    cache = default_cache_dir()
    return cache.parent / f"{cache.name}-plugin-index-{environment}-"


def has_index(key: str) -> bool:
    """True when an index was written under ``key``."""
    return index_path(key).is_file()


_READ: dict[str, dict[str, Any]] = {}  # the index last read, by its file (named by its key)


def _read(key: str) -> dict[str, Any] | None:
    """The index written under ``key``, its every byte checked; None without one.

    An index read once is kept while its file is there: the key in its name fixes what
    it holds (8 ms to read and check again at every discovery).

    The file is a header line (the key and a BLAKE2b digest of the rest) and
    the index as JSON. One that does not match its digest, does not parse or
    holds the wrong shapes (truncated, hand-edited, hostile: a node's entry missing
    a field or of another type, :data:`~graphvision.nodes.index_shape.INDEX`) is
    removed, so that the discovery that replaces it writes it again.
    """
    path = index_path(key)
    if str(path) in _READ and path.is_file() and _modules_unchanged(_READ[str(path)]):
        return _READ[str(path)]
    try:
        with open_regular(path) as stream:  # (a pipe there would block the read)
            data = stream.read()
    except OSError:
        return None
    header, _, body = data.partition(b"\n")
    try:
        head = json.loads(header)
        index = json.loads(body) if head == _header(key, body) else None
    except (ValueError, RecursionError):
        index = None
    if not isinstance(index, dict) or not fits(index, INDEX) or not _modules_unchanged(index):
        with contextlib.suppress(OSError):
            path.unlink()
        return None
    _READ.clear()
    _READ[str(path)] = index
    return index


def _modules_unchanged(index: dict[str, Any]) -> bool:
    """Whether the other top-level modules the plugins' import brought in (recorded by
    :func:`write_index`; not in the key, which is computed before any import) hold the
    bytes they held when the index was written."""
    recorded = index.get("modules", {})
    return all(package_digest(name).hex() == digest for name, digest in recorded.items())


def _header(key: str, body: bytes) -> dict[str, str]:
    return {"key": key, "blake2b": hashlib.blake2b(body, digest_size=20).hexdigest()}


def read_index(key: str) -> dict[str, Any] | None:
    """The nodes of the index written under ``key``, or None (see :func:`_read`)."""
    index = _read(key)
    return index["nodes"] if index is not None else None


def read_providers(key: str) -> dict[str, dict[str, Any]] | None:
    """For each entry-point plugin of the index under ``key``, the node ids, port type
    names, input-source schemes and implementations (``op@backend``) it registers, and
    the ``exclusive`` values of those implementations (read by
    :func:`graphvision.nodes.backends.exclusive_entries`); None without a sound index."""
    index = _read(key)
    return index["plugins"] if index is not None else None


def _exclusive(registry: Registry, plugin: str) -> dict[str, Any]:
    """The index's record of ``plugin``'s implementations with ``exclusive`` values (JSON
    scalars: one of another kind is not recorded, and is found when the plugin loads)."""
    scalars = (str, int, float, bool)
    return {
        f"{impl.op}@{impl.backend}": {
            "values": {
                name: [v for v in values if isinstance(v, scalars)]
                for name, values in impl.mark.exclusive
            },
            "hint": impl.install_hint,
        }
        for impls in registry.implementations.values()
        for impl in impls.values()
        if impl.plugin == plugin and impl.mark.exclusive
    }


def write_index(key: str, registry: Registry, modules: dict[str, bytes] | None = None) -> None:
    """Record ``registry``'s nodes under ``key``, with the digests of ``modules`` (the other
    top-level modules of the plugins' distributions, which the key does not cover), and
    remove this environment's older indexes (quietly nothing if the files cannot be
    written)."""
    nodes = {
        op: {"summary": spec.summary, "description": registry.describe(op)}
        for op, spec in sorted(registry.nodes.items())
    }
    plugins = {
        name: {
            "nodes": sorted(status.nodes),
            "port_types": sorted(status.port_types),
            "sources": sorted(status.sources),
            "implementations": sorted(status.implementations),
            "exclusive": _exclusive(registry, name),
        }
        for name, status in sorted(registry.plugins.items())
    }
    path = index_path(key)
    with contextlib.suppress(OSError, TypeError, ValueError):
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=".json")
        try:
            recorded = {name: digest.hex() for name, digest in sorted((modules or {}).items())}
            body = json.dumps({"nodes": nodes, "plugins": plugins, "modules": recorded}).encode()
            with os.fdopen(handle, "wb") as stream:
                stream.write(json.dumps(_header(key, body)).encode() + b"\n" + body)
            os.replace(temporary, path)
        finally:
            with contextlib.suppress(FileNotFoundError):
                os.remove(temporary)
        stem = _index_stem()
        for older in stem.parent.glob(f"{stem.name}*.json"):
            if older != path:
                with contextlib.suppress(OSError):
                    older.unlink()
