"""A shared store whose first write on a Dask worker kills that worker halfway through
(for tests/execution/test_dask_store.py; sent to the workers by value)."""

from __future__ import annotations

import os
import signal
import uuid
from typing import Any

from graphvision.cache.format import encode_blob
from graphvision.cache.shared import FsspecStore


class KillingStore(FsspecStore):
    """Kills the Dask worker it writes from, once (``marker`` says it did), with half of
    an entry written to the temporary name the store publishes from."""

    def __init__(self, url: str, max_bytes: int, options: dict[str, Any], marker: str) -> None:
        super().__init__(url, max_bytes, options)
        self.marker = marker

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        return (KillingStore, (self.url, self.max_bytes, self.storage_options, self.marker))

    def put(self, key: str, entry: Any) -> None:
        if _on_a_worker() and _first(self.marker, key):
            blob = b"".join(bytes(c) for c in encode_blob(entry))
            temp = f"{self.root}/{key[:2]}/.tmp-{uuid.uuid4().hex}.gvc"
            self.fs.pipe_file(temp, blob[: len(blob) // 2])
            os.kill(os.getpid(), signal.SIGKILL)
        super().put(key, entry)


def _first(marker: str, key: str) -> bool:
    """Whether this is the first write to kill its worker: ``marker`` made now, holding
    ``key`` (made exclusively: two workers writing at once, which both found no marker when
    it was looked at before it was written, both killed themselves)."""
    try:
        descriptor = os.open(marker, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:
        return False
    with os.fdopen(descriptor, "w") as handle:
        handle.write(key)
    return True


def _on_a_worker() -> bool:
    try:
        from distributed import get_worker

        get_worker()
    except (ImportError, ValueError):
        return False
    return True
