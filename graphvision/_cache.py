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
One file per output, ``<dir>/<key[:2]>/<key>.gvc``::

    b"GVC1" | header length (8 bytes, little endian) | JSON header | payload

The header holds the port type, its JSON metadata, each array's name, dtype,
shape and offset, and the xxh3-128 digest of the payload. Arrays are read back
with ``numpy.frombuffer`` (object dtypes are refused): there is no pickle to
load. Writes go to a temporary file in the same folder and are renamed into
place, so a reader, another process, or an interrupted run never sees half an
entry; a torn or altered file fails the digest, is dropped with a warning and
recomputed. Reads touch the file's mtime, which orders eviction (LRU).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import struct
import tempfile
import threading
import time
import warnings
from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import xxhash

from ._ports import PortType

__all__ = [
    "Cache",
    "CacheInfo",
    "CacheWarning",
    "DiskStore",
    "MemoryStore",
    "Store",
    "content_key",
    "default_cache_dir",
    "node_fingerprint",
    "output_key",
]

MAGIC = b"GVC1"
SUFFIX = ".gvc"
STALE_TEMP_SECONDS = 3600


class CacheWarning(UserWarning):
    """A cache problem that costs time but loses nothing (entry dropped, store disabled)."""


def default_cache_dir() -> Path:
    """``$GRAPHVISION_CACHE_DIR``, else ``$XDG_CACHE_HOME/graphvision``, else ``~/.cache/...``."""
    if os.environ.get("GRAPHVISION_CACHE_DIR"):
        return Path(os.environ["GRAPHVISION_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "graphvision"


# -- keys ---------------------------------------------------------------------------


def _hash_arrays(hasher: Any, arrays: dict[str, np.ndarray]) -> None:
    for name in sorted(arrays):
        array = np.ascontiguousarray(arrays[name])
        hasher.update(f"{name}|{array.dtype.str}|{array.shape}|".encode())
        hasher.update(memoryview(array).cast("B") if array.size else b"")


def content_key(port_type: type[PortType], value: Any) -> str:
    """Key of a graph-input value: hash of its type, header and array contents."""
    arrays, meta = port_type.encode(value)
    hasher = xxhash.xxh3_128()
    hasher.update(port_type.type_name().encode())
    hasher.update(json.dumps(meta, sort_keys=True, default=str).encode())
    _hash_arrays(hasher, arrays)
    return "i" + hasher.hexdigest()


def node_fingerprint(op: str, version: int, source_hash: str, params: dict[str, Any]) -> str:
    """Canonical text of what a node is: id, version, code fingerprint, parameters."""
    return json.dumps([op, version, source_hash, params], sort_keys=True, separators=(",", ":"))


def output_key(fingerprint: str, input_keys: dict[str, str], port: str) -> str:
    """Key of one node output, from everything that determines it (not from values).

    ``fingerprint`` comes from :func:`node_fingerprint`; input keys are taken
    in port order, so the key does not depend on how the graph was written.
    """
    inputs = "|".join(f"{name}={key}" for name, key in sorted(input_keys.items()))
    text = f"{fingerprint}\n{inputs}\n{port}"
    return hashlib.blake2b(text.encode(), digest_size=20).hexdigest()


# -- stores ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Encoded:
    """A value as its port type's named arrays plus JSON header."""

    type_name: str
    arrays: dict[str, np.ndarray]
    meta: dict[str, Any]

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in self.arrays.values()) + 256


class Store(Protocol):
    """Where encoded results live. One method each; swap in a fake for tests."""

    def get(self, key: str) -> Encoded | None: ...

    def put(self, key: str, entry: Encoded) -> None: ...

    def contains(self, key: str) -> bool: ...


class MemoryStore:
    """An LRU of decoded values bounded in bytes (thread-safe)."""

    def __init__(self, max_bytes: int = 512 * 2**20) -> None:
        self.max_bytes = max_bytes
        self._items: OrderedDict[str, tuple[Any, int]] = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()

    def get(self, key: str) -> Any | None:
        with self._lock:
            item = self._items.get(key)
            if item is None:
                return None
            self._items.move_to_end(key)
            return item[0]

    def put(self, key: str, value: Any, nbytes: int) -> None:
        if nbytes > self.max_bytes:
            return
        with self._lock:
            if key in self._items:
                self._bytes -= self._items.pop(key)[1]
            self._items[key] = (value, nbytes)
            self._bytes += nbytes
            while self._bytes > self.max_bytes:
                _, (_, size) = self._items.popitem(last=False)
                self._bytes -= size

    def contains(self, key: str) -> bool:
        return key in self._items

    def __len__(self) -> int:
        return len(self._items)

    @property
    def nbytes(self) -> int:
        return self._bytes


@dataclass(frozen=True)
class CacheInfo:
    directory: str
    entries: int
    bytes: int
    max_bytes: int


class DiskStore:
    """Content-verified files, atomic writes, LRU eviction; safe for several processes."""

    def __init__(self, directory: str | Path, max_bytes: int = 4 * 2**30) -> None:
        self.directory = Path(directory)
        self.max_bytes = max_bytes
        self._since_check = 0
        self._lock = threading.Lock()

    @classmethod
    def open(cls, directory: str | Path, max_bytes: int = 4 * 2**30) -> DiskStore | None:
        """The store at ``directory``, or None (with a warning) if it cannot be written."""
        store = cls(directory, max_bytes)
        try:
            store.directory.mkdir(parents=True, exist_ok=True)
            with tempfile.NamedTemporaryFile(dir=store.directory, prefix=".probe-"):
                pass
        except OSError as error:
            warnings.warn(
                f"cache directory {directory} is not writable ({error.strerror or error}); "
                "running without the disk cache",
                CacheWarning,
                stacklevel=2,
            )
            return None
        return store

    def path(self, key: str) -> Path:
        return self.directory / key[:2] / f"{key}{SUFFIX}"

    def contains(self, key: str) -> bool:
        return self.path(key).is_file()

    def get(self, key: str) -> Encoded | None:
        path = self.path(key)
        try:
            blob = path.read_bytes()
        except (FileNotFoundError, IsADirectoryError):
            return None
        try:
            entry = _decode_blob(blob)
        except ValueError as reason:
            warnings.warn(
                f"cache entry {path} is corrupt ({reason}); dropped, the result is recomputed",
                CacheWarning,
                stacklevel=2,
            )
            path.unlink(missing_ok=True)
            return None
        with contextlib.suppress(OSError):  # read-only cache, or pruned meanwhile: value is good
            os.utime(path)
        return entry

    def put(self, key: str, entry: Encoded) -> None:
        path = self.path(key)
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, temp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=SUFFIX)
        try:
            with os.fdopen(handle, "wb") as stream:
                for chunk in _encode_blob(entry):
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
        for sub in self.directory.iterdir() if self.directory.is_dir() else ():
            if not sub.is_dir():
                continue
            for path in sub.iterdir():
                try:
                    yield path, path.stat()
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
        now, freed, entries = time.time(), 0, []
        for path, stat in self._files():
            if path.name.startswith(".tmp-"):
                if now - stat.st_mtime > STALE_TEMP_SECONDS:
                    path.unlink(missing_ok=True)
                continue
            entries.append((stat.st_mtime, stat.st_size, path))
        total = sum(size for _, size, _ in entries)
        for _, size, path in sorted(entries):
            if total <= limit:
                break
            path.unlink(missing_ok=True)
            total -= size
            freed += size
        return freed

    def clear(self) -> int:
        """Remove every entry (and stray temporary files). Returns the number removed."""
        removed = 0
        for path, _ in list(self._files()):
            path.unlink(missing_ok=True)
            removed += not path.name.startswith(".")
        return removed


def _encode_blob(entry: Encoded) -> Iterator[bytes | memoryview]:
    specs, offset, digest = [], 0, xxhash.xxh3_128()
    arrays = {name: np.ascontiguousarray(a) for name, a in entry.arrays.items()}
    for name, array in arrays.items():
        if array.dtype.hasobject:
            raise TypeError(f"cannot cache object array '{name}'")
        specs.append(
            {
                "name": name,
                "dtype": array.dtype.str,
                "shape": list(array.shape),
                "offset": offset,
                "nbytes": array.nbytes,
            }
        )
        offset += array.nbytes
        digest.update(memoryview(array).cast("B") if array.size else b"")
    header = json.dumps(
        {
            "type": entry.type_name,
            "meta": entry.meta,
            "arrays": specs,
            "payload": offset,
            "digest": digest.hexdigest(),
        }
    ).encode()
    yield MAGIC + struct.pack("<Q", len(header)) + header
    for array in arrays.values():
        if array.size:
            yield memoryview(array).cast("B")


def _decode_blob(blob: bytes) -> Encoded:
    if len(blob) < 12 or blob[:4] != MAGIC:
        raise ValueError("not a graphvision cache entry")
    (length,) = struct.unpack("<Q", blob[4:12])
    try:
        header = json.loads(blob[12 : 12 + length])
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise ValueError(f"unreadable header: {error}") from None
    payload = memoryview(blob)[12 + length :]
    if len(payload) != header.get("payload"):
        raise ValueError(f"payload is {len(payload)} bytes, header says {header.get('payload')}")
    if xxhash.xxh3_128(payload).hexdigest() != header.get("digest"):
        raise ValueError("payload digest mismatch")
    arrays = {}
    for spec in header["arrays"]:
        dtype = np.dtype(spec["dtype"])
        if dtype.hasobject:
            raise ValueError("object dtype refused")
        count = int(np.prod(spec["shape"], dtype=np.int64))
        arrays[spec["name"]] = np.frombuffer(
            payload, dtype=dtype, count=count, offset=spec["offset"]
        ).reshape(spec["shape"])
    return Encoded(header["type"], arrays, header["meta"])


class Cache:
    """Memory in front of disk; either may be absent. Values go in and out decoded."""

    def __init__(self, memory: MemoryStore | None = None, disk: Store | None = None) -> None:
        self.memory = memory
        self.disk = disk

    def contains(self, key: str) -> bool:
        return bool(
            (self.memory and self.memory.contains(key)) or (self.disk and self.disk.contains(key))
        )

    def get(self, key: str, port_type: type[PortType]) -> tuple[bool, Any]:
        """(True, value) on a hit, (False, None) on a miss or an unusable entry."""
        if self.memory is not None:
            value = self.memory.get(key)
            if value is not None:
                return True, value
        if self.disk is None:
            return False, None
        entry = self.disk.get(key)
        if entry is None or entry.type_name != port_type.type_name():
            return False, None
        value = port_type.decode(entry.arrays, entry.meta)
        if self.memory is not None:
            self.memory.put(key, value, entry.nbytes)
        return True, value

    def put(self, key: str, port_type: type[PortType], value: Any) -> int:
        """Store ``value``; returns its encoded size in bytes."""
        arrays, meta = port_type.encode(value)
        entry = Encoded(port_type.type_name(), arrays, meta)
        if self.memory is not None:
            self.memory.put(key, value, entry.nbytes)
        if self.disk is not None:
            try:
                self.disk.put(key, entry)
            except OSError as error:
                warnings.warn(
                    f"could not write cache entry {key}: {error}; continuing",
                    CacheWarning,
                    stacklevel=2,
                )
        return entry.nbytes
