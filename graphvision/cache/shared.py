"""A cache store the machines of a cluster share: a folder of any fsspec filesystem.

:class:`FsspecStore` keeps the disk store's format and guarantees where the
store is an object store (S3 and S3-compatible servers, GCS, Azure) or any
other filesystem fsspec reaches:

- every entry is one object, ``<root>/<key[:2]>/<key>.gvc``, in the disk
  store's format (:mod:`graphvision.cache.format`): a digest over every byte
  after the fixed prefix, checked on read; an entry that fails is dropped with
  one warning and recomputed;
- a value is published atomically: written whole under a temporary name
  (``.tmp-<random>.gvc`` beside it) and then moved to its key, so a reader
  never sees half an entry, even when the writer is killed mid-write (on an
  object store the move is a server-side copy: the object appears whole or
  not at all); temporaries older than an hour are removed by :meth:`prune`;
- it touches only its own files: the root holds a ``CACHEDIR.TAG`` marker,
  a root that holds anything else is refused, and prune and clear remove only
  files of its own layout.

A store travels to another process as its URL and options (a batch's Dask
workers open it there and write their values into it;
:mod:`graphvision.execution.file_task`). A folder on a filesystem the
machines mount (NFS, SMB) is better served by
:class:`~graphvision.cache.disk.DiskStore`, whose writes are a local rename.

fsspec and the filesystem's own package (``s3fs`` for ``s3://``) are
imported only when such a store is made.
"""

from __future__ import annotations

import contextlib
import io
import time
import uuid
from collections.abc import Iterator
from datetime import datetime
from typing import Any

from graphvision.cache.disk import (
    MARKER,
    MARKER_TEXT,
    STALE_TEMP_SECONDS,
    SUFFIX,
    CacheInfo,
    evict_oldest,
    warn_dropped,
)
from graphvision.cache.entries import Encoded, NotACacheError
from graphvision.cache.format import decode_blob, encode_blob
from graphvision.values.memory import read_aligned

__all__ = ["FsspecStore", "open_store"]


class FsspecStore:
    """Verified entries, atomic publishing, only its own files: a store at an fsspec URL.

    Parameters
    ----------
    url : str
        The store's folder, e.g. ``s3://bucket/graphvision-cache`` or
        ``memory://cache``.
    max_bytes : int
        Size bound; :meth:`prune` evicts the least recently written entries
        beyond it (an object store keeps no access time).
    storage_options : dict, optional
        Passed to the filesystem (credentials, ``endpoint_url``...).

    Raises
    ------
    NotACacheError
        The folder holds files that are not this cache's.
    ValueError
        ``max_bytes`` is not positive.
    """

    def __init__(
        self,
        url: str,
        max_bytes: int = 4 * 2**30,
        storage_options: dict[str, Any] | None = None,
    ) -> None:
        import fsspec  # type: ignore[import-untyped]  # no types

        if max_bytes <= 0:
            raise ValueError(f"the cache size bound must be positive, got {max_bytes} bytes")
        self.url, self.max_bytes = url.rstrip("/"), max_bytes
        self.storage_options = dict(storage_options or {})
        self.fs, self.root = fsspec.core.url_to_fs(self.url, **self.storage_options)
        self.root = self.root.rstrip("/")
        self.read_only = False
        self._check_ownership()

    def __reduce__(self) -> tuple[Any, tuple[str, int, dict[str, Any]]]:
        """The store travels as its URL and options and is opened where it lands."""
        return (type(self), (self.url, self.max_bytes, self.storage_options))

    def _check_ownership(self) -> None:
        """Refuse a folder holding files this cache did not write; mark an empty one ours."""
        marker = f"{self.root}/{MARKER}"
        if self.fs.exists(marker):
            return
        foreign = [p for p in self._listing() if not _own_layout(self.root, p)]
        if foreign:
            shown = ", ".join(f"'{p[len(self.root) + 1 :]}'" for p in foreign[:3])
            raise NotACacheError(
                f"{self.url} is not a graphvision cache: it holds {shown}, which graphvision "
                "did not write; give the store a new or empty folder"
            )
        self.fs.pipe_file(marker, MARKER_TEXT.encode())

    def _listing(self) -> list[str]:
        try:
            return [str(p) for p in self.fs.find(self.root)]
        except FileNotFoundError:
            return []

    def path(self, key: str) -> str:
        return f"{self.root}/{key[:2]}/{key}{SUFFIX}"

    def get(self, key: str) -> Encoded | None:
        path = self.path(key)
        try:
            data = self.fs.cat_file(path)
        except FileNotFoundError:
            return None
        except OSError as error:
            self._drop(path, f"unreadable: {error}", remove=False)
            return None
        blob = read_aligned(io.BytesIO(data), len(data))
        try:
            return decode_blob(blob)
        except ValueError as reason:
            self._drop(path, str(reason), remove=not self.read_only)
            return None

    def _drop(self, path: str, reason: str, remove: bool) -> None:
        warn_dropped(path, reason)
        if remove:
            with contextlib.suppress(OSError):
                self.fs.rm_file(path)

    def put(self, key: str, entry: Encoded) -> None:
        """Write the entry whole under a temporary name, then move it to its key."""
        if self.read_only:
            return
        path = self.path(key)
        temp = f"{self.root}/{key[:2]}/.tmp-{uuid.uuid4().hex}{SUFFIX}"
        blob = b"".join(bytes(chunk) for chunk in encode_blob(entry))
        try:
            self.fs.pipe_file(temp, blob)
            self.fs.mv(temp, path)
        finally:
            with contextlib.suppress(OSError):
                if self.fs.exists(temp):
                    self.fs.rm_file(temp)

    def _files(self) -> Iterator[tuple[str, dict[str, Any]]]:
        """This store's entries and temporaries, with their details: its own layout only."""
        try:
            found = self.fs.find(self.root, detail=True)
        except FileNotFoundError:
            return
        for path, details in found.items():
            if _own_layout(self.root, str(path)) and not str(path).endswith(MARKER):
                yield str(path), details

    def info(self) -> CacheInfo:
        entries = [(p, d) for p, d in self._files() if not _name(p).startswith(".")]
        return CacheInfo(
            self.url, len(entries), sum(int(d.get("size") or 0) for _, d in entries), self.max_bytes
        )

    def prune(self, max_bytes: int | None = None) -> int:
        """Evict the oldest entries until at most ``max_bytes`` remain; remove stale
        temporaries of killed writers. Returns bytes freed."""
        limit = self.max_bytes if max_bytes is None else max_bytes
        now, entries = time.time(), []
        for path, details in self._files():
            written = _modified(details)
            if _name(path).startswith(".tmp-"):
                if now - written > STALE_TEMP_SECONDS:
                    self.fs.rm_file(path)
                continue
            entries.append((written, int(details.get("size") or 0), path))
        return evict_oldest(entries, limit, self.fs.rm_file)

    def clear(self) -> int:
        """Remove every entry and temporary. Returns the number of entries removed."""
        removed = 0
        for path, _ in list(self._files()):
            self.fs.rm_file(path)
            removed += not _name(path).startswith(".")
        return removed


def _name(path: str) -> str:
    return path.rsplit("/", 1)[-1]


def _own_layout(root: str, path: str) -> bool:
    """The marker, ``<shard>/<key>.gvc`` with the key starting with the shard, or a temporary."""
    parts = path[len(root) + 1 :].split("/") if path.startswith(root + "/") else []
    if parts == [MARKER]:
        return True
    if len(parts) != 2 or len(parts[0]) != 2 or not parts[1].endswith(SUFFIX):
        return False
    return parts[1].startswith(parts[0]) or parts[1].startswith(".tmp-")


def _modified(details: dict[str, Any]) -> float:
    """Seconds since the epoch an object was last written, from its listing's details."""
    for field in ("LastModified", "mtime", "created"):
        value = details.get(field)
        if isinstance(value, datetime):
            return value.timestamp()
        if isinstance(value, int | float):
            return float(value)
    return time.time()


def open_store(location: str, max_bytes: int = 4 * 2**30, **storage_options: Any) -> Any:
    """A store at ``location``: a :class:`~graphvision.cache.disk.DiskStore` for a plain
    folder (or ``file://``), an :class:`FsspecStore` for any other fsspec URL."""
    from graphvision.cache.disk import DiskStore

    scheme, sep, rest = location.partition("://")
    if not sep:
        return DiskStore.open(location, max_bytes)
    if scheme == "file":
        return DiskStore.open(rest, max_bytes)
    return FsspecStore(location, max_bytes, storage_options)
