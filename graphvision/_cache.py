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
checked too (a JSON object, the fields and their types, offsets at multiples
of 64, sizes that add up to the payload), so an entry is used only if it is
whole. The payload and every array in it start at a multiple of 64 bytes, and
a file is read into an immutable buffer that starts at a 64-byte aligned
address (:mod:`graphvision._memory`), so arrays read back with
``numpy.frombuffer`` are aligned exactly as computed values are (a reduction
over them takes the same path and gives the same bits), cannot be made
writable, and hold no pickle (object dtypes are refused).

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
import hashlib
import json
import os
import re
import struct
import tempfile
import threading
import time
import warnings
from collections import OrderedDict
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import xxhash

from ._cache_dir import default_cache_dir
from ._errors import GraphvisionError
from ._memory import ALIGNMENT, read_aligned
from ._ports import PortType

__all__ = [
    "Cache",
    "CacheInfo",
    "CacheWarning",
    "DiskStore",
    "MemoryStore",
    "NotACacheError",
    "Store",
    "content_key",
    "default_cache_dir",
    "node_fingerprint",
    "output_key",
    "output_keys",
]

MAGIC = b"GVC3"
SUFFIX = ".gvc"
STALE_TEMP_SECONDS = 3600
MARKER = "CACHEDIR.TAG"
MARKER_TEXT = (
    "Signature: 8a477f597d28d172789f06886806bc55\n"
    "# This file is a cache directory tag created by graphvision.\n"
    "# For information about cache directory tags see https://bford.info/cachedir/\n"
)
_PREFIX = struct.Struct("<4sQ16s")  # magic, header length, digest of header + payload
_TEMP = re.compile(r"^\.tmp-[A-Za-z0-9_]+\.gvc$")


class CacheWarning(UserWarning):
    """A cache problem that costs time but loses nothing (entry dropped, store disabled)."""


class NotACacheError(GraphvisionError):
    """A cache directory was asked for in a folder that holds other files."""


# -- keys ---------------------------------------------------------------------------


def _hash_arrays(hasher: Any, arrays: dict[str, np.ndarray]) -> None:
    for name in sorted(arrays):
        array = np.ascontiguousarray(arrays[name])
        hasher.update(f"{name}|{array.dtype.str}|{array.shape}|".encode())
        hasher.update(array.data.cast("B") if array.size else b"")


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
    return output_keys(fingerprint, input_keys, (port,))[0]


def output_keys(fingerprint: str, input_keys: dict[str, str], ports: Iterable[str]) -> list[str]:
    """:func:`output_key` of each of a node's ``ports`` (the inputs' part written once)."""
    if len(input_keys) == 1:  # most nodes: the same text without sorting (0.45 µs of 1.2)
        [(name, key)] = input_keys.items()
        inputs = f"{name}={key}"
    else:
        inputs = "|".join([f"{name}={key}" for name, key in sorted(input_keys.items())])
    head = f"{fingerprint}\n{inputs}\n"
    return [hashlib.blake2b(f"{head}{port}".encode(), digest_size=20).hexdigest() for port in ports]


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
        ``max_bytes`` is not positive.
    """

    def __init__(self, directory: str | Path, max_bytes: int = 4 * 2**30) -> None:
        if max_bytes <= 0:
            raise ValueError(f"the cache size bound must be positive, got {max_bytes} bytes")
        self.directory = Path(directory)
        self.max_bytes = max_bytes
        self.read_only = False
        self._since_check = 0
        self._lock = threading.Lock()
        self._check_ownership()

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
            store.directory.mkdir(parents=True, exist_ok=True)
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
            with path.open("rb") as stream:
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
        warnings.warn(
            f"cache entry {path} is corrupt ({reason}); dropped, the result is recomputed",
            CacheWarning,
            stacklevel=3,
        )
        if remove:
            with contextlib.suppress(OSError):
                path.unlink()

    def put(self, key: str, entry: Encoded) -> None:
        if self.read_only:
            return
        path = self.path(key)
        if not self.directory.is_dir():
            self.directory.mkdir(parents=True, exist_ok=True)
        if not (self.directory / MARKER).is_file():
            (self.directory / MARKER).write_text(MARKER_TEXT)
        path.parent.mkdir(exist_ok=True)
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


def _is_shard(item: Path) -> bool:
    """A shard folder of the layout: two characters, a real folder (not a link)."""
    return len(item.name) == 2 and item.is_dir() and not item.is_symlink()


def _is_own_file(shard: Path, path: Path) -> bool:
    """An entry ``<shard>/<key>.gvc`` with the key starting with the shard, or a temp file."""
    name = path.name
    if path.is_symlink() or not name.endswith(SUFFIX):
        return False
    return name.startswith(shard.name) or bool(_TEMP.match(name))


def _padded(offset: int) -> int:
    """``offset`` rounded up to a multiple of :data:`ALIGNMENT`."""
    return -(-offset // ALIGNMENT) * ALIGNMENT


def encode_blob(entry: Encoded) -> Iterator[bytes | memoryview]:
    """The bytes of a disk entry for ``entry``, in chunks (arrays are not copied)."""
    specs, chunks, offset = [], [], 0
    arrays = {name: np.ascontiguousarray(a) for name, a in entry.arrays.items()}
    for name, array in arrays.items():
        if array.dtype.hasobject:
            raise TypeError(f"cannot cache object array '{name}'")
        start = _padded(offset)
        if array.size:
            chunks += [bytes(start - offset), array.data.cast("B")]
            offset = start + array.nbytes
        specs.append(
            {
                "name": name,
                "dtype": array.dtype.str,
                "shape": list(array.shape),
                "offset": start if array.size else offset,
                "nbytes": array.nbytes,
            }
        )
    header = json.dumps(
        {"type": entry.type_name, "meta": entry.meta, "arrays": specs, "payload": offset}
    ).encode()
    chunks.insert(0, bytes(_padded(_PREFIX.size + len(header)) - _PREFIX.size - len(header)))
    digest = xxhash.xxh3_128(header)
    for chunk in chunks:
        digest.update(chunk)
    yield _PREFIX.pack(MAGIC, len(header), digest.digest()) + header
    yield from chunks


def decode_blob(blob: bytes | memoryview) -> Encoded:
    """The entry in ``blob``, after checking every byte; ValueError says what is wrong.

    Arrays are views of ``blob``: aligned when ``blob`` starts at a multiple of
    :data:`ALIGNMENT` (as :func:`~graphvision._memory.read_aligned` gives).
    """
    if len(blob) < _PREFIX.size:
        raise ValueError(f"truncated: {len(blob)} bytes")
    magic, length, digest = _PREFIX.unpack_from(blob)
    if magic != MAGIC:
        raise ValueError("not a graphvision cache entry of this version")
    if length > len(blob) - _PREFIX.size:
        raise ValueError("truncated: the header runs past the end of the file")
    body = memoryview(blob)[_PREFIX.size :]
    if xxhash.xxh3_128(body).digest() != digest:
        raise ValueError("digest mismatch: the file was altered or cut short")
    try:
        header = json.loads(bytes(body[:length]))
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise ValueError(f"unreadable header: {error}") from None
    payload = memoryview(blob)[_padded(_PREFIX.size + length) :]
    specs = _check_header(header, len(payload))
    arrays = {}
    for name, dtype, shape, offset in specs:
        count = int(np.prod(shape, dtype=np.int64))
        arrays[name] = np.frombuffer(payload, dtype=dtype, count=count, offset=offset).reshape(
            shape
        )
    return Encoded(header["type"], arrays, header["meta"])


def _check_header(
    header: Any, payload_bytes: int
) -> list[tuple[str, np.dtype, tuple[int, ...], int]]:
    """(name, dtype, shape, offset) of each array, or ValueError naming what does not hold."""
    if not isinstance(header, dict):
        raise ValueError("the header is not a JSON object")
    for field, kind in (("type", str), ("meta", dict), ("arrays", list), ("payload", int)):
        if not isinstance(header.get(field), kind):
            raise ValueError(f"the header's '{field}' is missing or not a {kind.__name__}")
    if header["payload"] != payload_bytes:
        raise ValueError(f"payload is {payload_bytes} bytes, header says {header['payload']}")
    specs, expected_offset = [], 0
    for spec in header["arrays"]:
        try:
            name, shape = str(spec["name"]), tuple(int(n) for n in spec["shape"])
            dtype = np.dtype(spec["dtype"])
            offset, nbytes = int(spec["offset"]), int(spec["nbytes"])
        except (KeyError, TypeError, ValueError) as error:
            raise ValueError(f"an array description is malformed ({error})") from None
        if dtype.hasobject:
            raise ValueError("object dtype refused")
        start = _padded(expected_offset) if nbytes else expected_offset
        if any(n < 0 for n in shape) or offset != start:
            raise ValueError(f"array '{name}' has a bad shape or offset")
        if nbytes != int(np.prod(shape, dtype=np.int64)) * dtype.itemsize:
            raise ValueError(f"array '{name}': shape {list(shape)} disagrees with {nbytes} bytes")
        specs.append((name, dtype, shape, offset))
        expected_offset = start + nbytes
    if expected_offset != payload_bytes:
        raise ValueError(f"arrays add up to {expected_offset} bytes, payload is {payload_bytes}")
    return specs


class Cache:
    """Memory in front of disk; either may be absent. Values go in and out decoded.

    ``Cache.at(folder)`` is the usual one: memory in front of a disk cache in
    ``folder`` (created, or checked to be a graphvision cache).
    """

    def __init__(self, memory: MemoryStore | None = None, disk: Store | None = None) -> None:
        for name, store in (("memory", memory), ("disk", disk)):
            if store is not None and not (hasattr(store, "get") and hasattr(store, "put")):
                raise TypeError(
                    f"Cache({name}=...) takes a store, got {type(store).__name__}: "
                    "for a cache in a folder use graphvision.Cache.at(folder)"
                )
        if memory is not None and not isinstance(memory, MemoryStore):  # it holds decoded values
            raise TypeError(
                f"Cache(memory=...) takes a MemoryStore, got {type(memory).__name__}: a disk "
                "store goes second, Cache(disk=store), or use graphvision.Cache.at(folder)"
            )
        self.memory = memory
        self.disk = disk

    @classmethod
    def at(cls, directory: str | Path, max_bytes: int = 4 * 2**30) -> Cache:
        """Memory in front of the disk cache in ``directory``, bounded to ``max_bytes``.

        Raises
        ------
        NotACacheError
            When ``directory`` holds files that are not a graphvision cache.
        """
        return cls(MemoryStore(), DiskStore.open(directory, max_bytes))

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
        try:
            value = port_type.decode(entry.arrays, entry.meta)
        except Exception as error:  # whole and verified, yet not a value of its type
            warnings.warn(
                f"cache entry {key} does not decode as {port_type.type_name()} ({error}); "
                "dropped, the result is recomputed",
                CacheWarning,
                stacklevel=2,
            )
            return False, None
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
