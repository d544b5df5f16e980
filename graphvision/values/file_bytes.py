"""An input file's bytes read whole, their SHA-256 and resolved path kept for the provenance.

A run's record holds, for each input file, its path resolved and the SHA-256
of its bytes (:mod:`graphvision.execution.provenance`). Hashing the file after
the run opened and read it a second time, and resolving its path made a system
call per folder on the way (13 calls for a PNG of a batch, each releasing the
GIL and taking it back: a wait on a batch on threads, where the other file's
thread holds it), although the reader had held its bytes and the file open. A
reader that reads a file through :func:`read_file_bytes` has them hashed there,
once:

    sha256 = SHA-256(the bytes read) (FIPS 180-4),

and the file's path named by the kernel from the open file (Linux's
``/proc/self/fd``: the path it was opened by, every link on the way followed,
as ``Path.resolve`` follows them). Both are kept by the path given and the stamp
of the file read (device, inode, size and modification time in ns, taken with
``fstat`` on the open file): the provenance of the run looks them up with one
``stat`` of the path, so a file changed or replaced since it was read has
another stamp and is hashed and resolved again, as before.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

__all__ = ["read_before", "read_file_bytes"]

_KEEP = 256
"""Files kept (the files read lately: a batch on two threads reads two at a time)."""

_Key = tuple[str, int, int, int, int]

_READ: dict[_Key, tuple[str, str | None]] = {}


def _key(path: str | Path, info: os.stat_result) -> _Key:
    return (os.fspath(path), info.st_dev, info.st_ino, info.st_size, info.st_mtime_ns)


def read_file_bytes(path: str | Path, limit: int | None = None) -> bytes | None:
    """The bytes of the file at ``path``, read in one go, or None (nothing read) when it
    holds more than ``limit`` bytes.

    Six system calls for a file that does not grow meanwhile (open, ``fstat``, a read of
    its size, the read that finds its end, the ``readlink`` naming it, close). The SHA-256
    of the bytes and the path resolved are kept for the provenance of the run reading the
    file (:func:`read_before`) when the bytes are as many as ``fstat`` said (else the file
    changed while it was read: the provenance hashes it again); a file read again with the
    same stamp is not hashed again (as the provenance kept a file's digest by its stamp).

    Raises
    ------
    OSError
        As ``open`` does (``FileNotFoundError``, ``PermissionError``, ...).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     file = Path(folder, "a.txt")
    ...     _ = file.write_bytes(b"abc")
    ...     data = read_file_bytes(file)
    ...     digest, _ = read_before(file, os.stat(file))
    >>> data, digest == hashlib.sha256(b"abc").hexdigest()
    (b'abc', True)
    """
    descriptor = os.open(path, os.O_RDONLY | getattr(os, "O_BINARY", 0))  # (binary on Windows)
    try:
        info = os.fstat(descriptor)
        if limit is not None and info.st_size > limit:
            return None
        chunks = []
        while chunk := os.read(descriptor, max(info.st_size, 1 << 16)):  # (all of one grown)
            chunks.append(chunk)
        where = _opened_path(descriptor)
    finally:
        os.close(descriptor)
    data = b"".join(chunks)
    if len(data) == info.st_size:
        key = _key(path, info)
        known = _READ.get(key)  # read before, unchanged since: the same bytes, hashed once
        digest = known[0] if known is not None else hashlib.sha256(data).hexdigest()
        if len(_READ) >= _KEEP:
            _READ.clear()
        _READ[key] = (digest, where)
    return data


def _opened_path(descriptor: int) -> str | None:
    """The path of the file open as ``descriptor``, as the kernel names it (Linux); None
    where it does not (another system, no ``/proc``, a file removed since it was opened)."""
    try:
        where = os.readlink(f"/proc/self/fd/{descriptor}")
    except OSError:
        return None
    return where if where.startswith("/") and not where.endswith(" (deleted)") else None


def read_before(path: str | Path, info: os.stat_result) -> tuple[str, str | None] | None:
    """The SHA-256 of the bytes :func:`read_file_bytes` read from ``path`` and the path it
    resolved to (None where the system did not name it), if it read them in this process
    since the file at ``path`` was last changed (``info`` is its ``os.stat``); else None."""
    return _READ.get(_key(path, info))
