"""The cache a run uses: an optional memory store in front of an optional disk store,
validating and freezing what it hands back."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

from graphvision.cache.entries import CacheWarning, Encoded, Store
from graphvision.cache.memory_store import MemoryStore
from graphvision.values.ports import PortType

__all__ = [
    "Cache",
]


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
    def at(cls, directory: str | Path, max_bytes: int = 4 * 2**30, **storage_options: Any) -> Cache:
        """Memory in front of the store at ``directory``, bounded to ``max_bytes``.

        ``directory`` is a folder (a :class:`DiskStore`), or the URL of a folder
        on a filesystem fsspec reaches (``s3://bucket/cache``: an
        :class:`~graphvision.cache.shared.FsspecStore`, ``storage_options``
        passed to it), which the workers of a cluster can share.

        Raises
        ------
        NotACacheError
            When ``directory`` holds files that are not a graphvision cache.
        """
        from graphvision.cache.shared import open_store

        return cls(MemoryStore(), open_store(str(directory), max_bytes, **storage_options))

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
