"""The result cache: Merkle keys, an in-memory LRU and an on-disk store.

Keys
----
A graph input's key hashes its content (port type, header, and each array's
dtype, shape and bytes with xxh3-128, >30 GB/s). A node output's key hashes
(node id, version, fingerprint of the node's source, canonical parameters,
the keys of its inputs, the port name), so keys chain like a Merkle tree and
no intermediate value is ever hashed.

Disk format
-----------
A cache directory holds a marker, ``CACHEDIR.TAG`` (the Cache Directory
Tagging convention, so backup tools skip it, with a line naming graphvision),
and one file per output, ``<dir>/<key[:2]>/<key>.gvc``::

    b"GVC3" | header length (8 bytes, little endian) | digest (16 bytes) | JSON header
            | zeros to a multiple of 64 bytes | payload

The digest is xxh3-128 of everything after it (header, padding and payload),
so every byte after the fixed prefix is verified before any of it is used.
The header holds the port type, its JSON metadata, and each array's name,
dtype, shape, offset and size; after the digest, the header's structure is
checked too (a JSON object, the fields and their types, offsets under 64 bytes
past multiples of 64 and aligned for the dtype, sizes that add up to the
payload), so an entry is used only if it is whole. The payload starts at a
multiple of 64 bytes, every array in it at a multiple of 64 plus the offset
the value had past one when it was stored (its address modulo 64, a multiple
of its dtype's alignment), and a file is read into an immutable buffer that
starts at a 64-byte aligned address (:mod:`graphvision.values.memory`), so
arrays read back with ``numpy.frombuffer`` lie exactly as the computed values
did (a reduction over them takes the same path and gives the same bits),
cannot be made writable, and hold no pickle (object dtypes are refused).

Writes go to a temporary file in the same folder and are renamed into place,
so a reader, another process, or an interrupted run never sees half an
entry. Any entry that fails a check is dropped with one warning line and
recomputed. Reads touch the file's mtime, which orders eviction (LRU).

The cache touches only what it wrote: it refuses a non-empty folder without
its marker (``--cache-dir ~/thesis`` is an error, not a purge), and pruning
and clearing remove only files of its own layout.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from graphvision.cache.entries import CacheWarning, Encoded, NotACacheError
from graphvision.cache.format import decode_blob, encode_blob
from graphvision.locations import open_regular
from graphvision.values.memory import read_aligned

__all__ = [
    "MARKER",
    "SUFFIX",
    "CacheInfo",
    "DiskStore",
    "warn_dropped",
]


SUFFIX = ".gvc"
STALE_TEMP_SECONDS = 3600
MARKER = "CACHEDIR.TAG"
MARKER_TEXT = (
    "Signature: 8a477f597d28d172789f06886806bc55\n"
    "# This file is a cache directory tag created by graphvision.\n"
    "# For information about cache directory tags see https://bford.info/cachedir/\n"
)
EntryPath = TypeVar("EntryPath", Path, str)
_TEMP = re.compile(r"^\.tmp-[A-Za-z0-9_]+\.gvc$")


@dataclass(frozen=True)
class CacheInfo:
    directory: str
    entries: int
    bytes: int
    max_bytes: int


def evict_oldest(
    entries: list[tuple[float, int, EntryPath]], limit: int, remove: Callable[[EntryPath], None]
) -> int:
    """Remove the oldest of ``(time, size, path)`` entries until their sizes sum to at
    most ``limit`` (least recently used first). Returns the bytes freed."""
    total, freed = sum(size for _, size, _ in entries), 0
    for _, size, path in sorted(entries):
        if total <= limit:
            break
        remove(path)
        total -= size
        freed += size
    return freed


def warn_dropped(path: object, reason: str) -> None:
    """The warning a store gives for a corrupt entry it drops (the caller recomputes it)."""
    warnings.warn(
        f"cache entry {path} is corrupt ({reason}); dropped, the result is recomputed",
        CacheWarning,
        stacklevel=4,
    )


class DiskStore:
    """Verified files, atomic writes, LRU eviction; safe for several processes.

    Parameters
    ----------
    directory : path
        The cache folder: new, empty, or a graphvision cache (it has the
        marker). A folder holding anything else is refused.
    max_bytes : int
        Size bound; least recently used entries are evicted beyond it.

    Raises
    ------
    NotACacheError
        ``directory`` is a file, or a non-empty folder that is not a graphvision cache.
    ValueError
        ``max_bytes`` is not positive, or ``directory`` is an empty path.
    """

    def __init__(self, directory: str | Path, max_bytes: int = 4 * 2**30) -> None:
        if max_bytes <= 0:
            raise ValueError(f"the cache size bound must be positive, got {max_bytes} bytes")
        if not str(directory).strip():  # Path('') would be this folder
            raise ValueError("the cache folder is an empty path: give a folder (. for this one)")
        self.directory = Path(directory)
        self.max_bytes = max_bytes
        self.read_only = False
        self._since_check = 0
        self._lock = threading.Lock()
        self._check_ownership()

    def __reduce__(self) -> tuple[Any, tuple[str, int, bool]]:
        """A store travels to another process as its location: the folder is opened there
        (a batch's workers write their values into the cache the client reads)."""
        return (_reopened, (str(self.directory.absolute()), self.max_bytes, self.read_only))

    def _check_ownership(self) -> None:
        """Refuse a folder that holds files this cache did not write (see the module docs)."""
        folder = self.directory
        if folder.exists() and not folder.is_dir():
            raise NotACacheError(f"cache directory {folder} is a file, not a folder")
        if not folder.is_dir() or (folder / MARKER).is_file():
            return
        foreign = [
            item.name
            for item in sorted(folder.iterdir())
            if not (_is_shard(item) and all(_is_own_file(item, f) for f in item.iterdir()))
        ]
        if foreign:
            shown = ", ".join(f"'{name}'" for name in foreign[:3])
            more = f" and {len(foreign) - 3} more" if len(foreign) > 3 else ""
            raise NotACacheError(
                f"{folder} is not a graphvision cache: it holds {shown}{more}, which "
                "graphvision did not write; give --cache-dir a new or empty folder"
            )
        with contextlib.suppress(OSError):  # adopt a folder of our own layout (older versions)
            (folder / MARKER).write_text(MARKER_TEXT)

    @classmethod
    def open(cls, directory: str | Path, max_bytes: int = 4 * 2**30) -> DiskStore | None:
        """The store at ``directory``; read-only (with one warning) when it cannot be written.

        Returns None, with a warning, when the folder neither exists nor can be made.
        """
        store = cls(directory, max_bytes)
        try:
            _owner_only_folder(store.directory, parents=True)
        except OSError as error:
            warnings.warn(
                f"cache directory {directory} cannot be created ({error.strerror or error}); "
                "running without the disk cache",
                CacheWarning,
                stacklevel=2,
            )
            return None
        try:
            if not (store.directory / MARKER).is_file():
                (store.directory / MARKER).write_text(MARKER_TEXT)
            with tempfile.NamedTemporaryFile(dir=store.directory, prefix=".probe-"):
                pass
        except OSError as error:
            store.read_only = True
            warnings.warn(
                f"cache directory {directory} is read-only ({error.strerror or error}); "
                "cached results are read from it, new results are not stored",
                CacheWarning,
                stacklevel=2,
            )
        return store

    def path(self, key: str) -> Path:
        return self.directory / key[:2] / f"{key}{SUFFIX}"

    def get(self, key: str) -> Encoded | None:
        path = self.path(key)
        try:
            with open_regular(path) as stream:  # (a pipe there would block the read)
                blob = read_aligned(stream, os.fstat(stream.fileno()).st_size)
        except FileNotFoundError:
            return None
        except EOFError as error:  # cut short while it was read: replaced meanwhile
            self._drop(path, f"truncated while read: {error}", remove=False)
            return None
        except OSError as error:  # a shard replaced by a file, an entry by a folder, no access
            self._drop(path, f"unreadable: {error.strerror or error}", remove=False)
            return None
        try:
            entry = decode_blob(blob)
        except ValueError as reason:
            self._drop(path, str(reason), remove=not self.read_only)
            return None
        with contextlib.suppress(OSError):  # read-only cache, or pruned meanwhile: value is good
            os.utime(path)
        return entry

    def _drop(self, path: Path, reason: str, remove: bool) -> None:
        warn_dropped(path, reason)
        if remove:
            with contextlib.suppress(OSError):
                path.unlink()

    def put(self, key: str, entry: Encoded) -> None:
        if self.read_only:
            return
        path = self.path(key)
        if not self.directory.is_dir():
            _owner_only_folder(self.directory, parents=True)
        if not (self.directory / MARKER).is_file():
            (self.directory / MARKER).write_text(MARKER_TEXT)
        if not path.parent.is_dir():
            _owner_only_folder(path.parent)
        handle, temp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=SUFFIX)
        try:
            with os.fdopen(handle, "wb") as stream:
                for chunk in encode_blob(entry):
                    stream.write(chunk)
            os.replace(temp, path)
        except BaseException:
            Path(temp).unlink(missing_ok=True)
            raise
        with self._lock:
            self._since_check += entry.nbytes
            due = self._since_check > self.max_bytes // 10
            if due:
                self._since_check = 0
        if due:
            self.prune(self.max_bytes)

    def _files(self) -> Iterator[tuple[Path, os.stat_result]]:
        """The entries and temporary files of this store: its own layout, nothing else."""
        for shard in self.directory.iterdir() if self.directory.is_dir() else ():
            if not _is_shard(shard):
                continue
            for path in shard.iterdir():
                if not _is_own_file(shard, path):
                    continue
                try:
                    yield path, path.stat(follow_symlinks=False)
                except FileNotFoundError:
                    continue

    def info(self) -> CacheInfo:
        entries = [(p, s) for p, s in self._files() if not p.name.startswith(".")]
        return CacheInfo(
            str(self.directory), len(entries), sum(s.st_size for _, s in entries), self.max_bytes
        )

    def prune(self, max_bytes: int | None = None) -> int:
        """Evict least recently used entries until the store holds at most ``max_bytes``.

        Also removes temporary files left by interrupted writers. Returns bytes freed.
        """
        limit = self.max_bytes if max_bytes is None else max_bytes
        now, entries = time.time(), []
        for path, stat in self._files():
            if path.name.startswith(".tmp-"):
                if now - stat.st_mtime > STALE_TEMP_SECONDS:
                    path.unlink(missing_ok=True)
                continue
            entries.append((stat.st_mtime, stat.st_size, path))
        return evict_oldest(entries, limit, lambda path: path.unlink(missing_ok=True))

    def clear(self) -> int:
        """Remove every entry (and stray temporary files). Returns the number removed."""
        removed = 0
        for path, _ in list(self._files()):
            path.unlink(missing_ok=True)
            removed += not path.name.startswith(".")
        return removed


def _reopened(directory: str, max_bytes: int, read_only: bool) -> DiskStore:
    """The store at ``directory`` in this process (see :meth:`DiskStore.__reduce__`)."""
    store = DiskStore(directory, max_bytes)
    store.read_only = read_only
    return store


def _owner_only_folder(folder: Path, parents: bool = False) -> None:
    """Make ``folder`` readable and writable by its owner only, whatever the umask (at
    umask 000 ``mkdir`` made shard folders anyone could write into). Entries are made by
    ``mkstemp`` (0600) and renamed, so they are the owner's only too. A folder that
    existed before (the user's) keeps its mode."""
    if folder.is_dir():
        return
    folder.mkdir(mode=0o700, parents=parents, exist_ok=True)
    with contextlib.suppress(OSError):
        os.chmod(folder, 0o700)


def _is_shard(item: Path) -> bool:
    """A shard folder of the layout: two characters, a real folder (not a link)."""
    return len(item.name) == 2 and item.is_dir() and not item.is_symlink()


def _is_own_file(shard: Path, path: Path) -> bool:
    """An entry ``<shard>/<key>.gvc`` with the key starting with the shard, or a temp file."""
    name = path.name
    if path.is_symlink() or not name.endswith(SUFFIX):
        return False
    return name.startswith(shard.name) or bool(_TEMP.match(name))
