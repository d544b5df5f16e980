"""How values cross between the studio's server and its worker processes.

A message is pickled with its arrays out of band (protocol 5), each array's bytes written
once. A small array goes through the socket. From ``SHARED_BYTES`` up, arrays are copied
into the channel's *arena*: a memory file (Linux's ``memfd_create``) that the sender made
once and both processes keep mapped, reused by every later message in that direction. Its
pages are allocated once: a new memory file per value cost about 8 ms of CPU for the 6 MB
matches picture (the kernel allocating and zeroing its pages), a copy into pages already
there about 0.4 ms. The arena grows (a new memory file, its descriptor crossing the socket
with the message) when a message needs more, up to ``ARENA_BYTES``; a larger message, or
one sent before the peer has answered the last one, takes memory files of its own.

The receiver copies each shared array out at once, into immutable memory aligned as the
engine's values are (:func:`graphvision.values.memory.aligned_bytes`): the arena is free
for the next message, and the value needs no second copy to be frozen. The arena is
reused only once the peer has answered, so only after it read the last message in full:
the studio's worker protocol is a strict exchange (a node, then its result).

Without ``memfd_create`` (not Linux), or on a pipe that cannot carry descriptors, every
array goes through the pipe.
"""

from __future__ import annotations

import contextlib
import mmap
import os
import pickle
import socket
from typing import Any

import numpy as np

from graphvision.values.memory import ALIGNMENT, aligned_bytes

__all__ = ["ARENA_BYTES", "SHARED_BYTES", "Channel"]

SHARED_BYTES = 1 << 16  # an array this large travels in shared memory, not the socket
ARENA_BYTES = 1 << 26  # the largest arena kept; a larger message has files of its own

# How each out-of-band buffer of a message travels (one byte each in its head).
_PIPE, _ARENA, _FILE = 0, 1, 2


class Channel:
    """One end of a connection between two processes, with its arenas (module docstring).

    Parameters
    ----------
    connection : multiprocessing.connection.Connection
        Over a socket (a socket pair) to share memory; any connection otherwise.
    """

    def __init__(self, connection: Any) -> None:
        self.connection = connection
        self.out: mmap.mmap | None = None  # the arena this end writes (it made it)
        self.into: mmap.mmap | None = None  # the arena the peer writes, mapped here
        self.unanswered = False  # the peer has not answered since this end used its arena

    def fileno(self) -> int:
        return int(self.connection.fileno())

    def close(self) -> None:
        """Close the connection and let go of both arenas."""
        self.connection.close()
        for arena in (self.out, self.into):
            if arena is not None:
                with contextlib.suppress(BufferError):
                    arena.close()
        self.out = self.into = None

    def send(self, message: Any) -> None:
        """Send ``message``: small arrays through the socket, the others shared."""
        buffers: list[pickle.PickleBuffer] = []
        head = pickle.dumps(message, protocol=5, buffer_callback=buffers.append)
        raws = [buffer.raw() for buffer in buffers]
        large = [r.nbytes >= SHARED_BYTES for r in raws]
        carrier = _socket_of(self.connection) if any(large) else None
        try:
            ways, offsets, grown = self._place(raws, large if carrier is not None else [])
            files = [grown] if grown is not None else []
            for raw, way in zip(raws, ways, strict=True):
                if way == _FILE:
                    files.append(_memory_file(raw))
            try:
                sizes = [r.nbytes for r in raws]
                layout = np.array([offsets, sizes], dtype=np.int64).T.tobytes()
                self.connection.send_bytes(
                    len(raws).to_bytes(4, "little") + bytes(ways)
                    + bytes([grown is not None]) + layout + head
                )  # fmt: skip
                for raw, way in zip(raws, ways, strict=True):
                    if way == _PIPE:
                        self.connection.send_bytes(raw)
                if carrier is not None and files:
                    socket.send_fds(carrier, [b"F"], files)
            finally:
                for file in files:
                    os.close(file)
        finally:
            if carrier is not None:
                carrier.close()

    def _place(
        self, raws: list[memoryview], large: list[bool]
    ) -> tuple[list[int], list[int], int | None]:
        """How each buffer travels, the arena offset of each (0 when not there), and the
        descriptor of a new, larger arena (None: the same one), its buffers copied in."""
        ways = [_FILE if big else _PIPE for big in large] + [_PIPE] * (len(raws) - len(large))
        offsets = [0] * len(raws)
        total = sum(_padded(r.nbytes) for r, w in zip(raws, ways, strict=True) if w == _FILE)
        if not total or total > ARENA_BYTES or self.unanswered:
            return ways, offsets, None
        grown = None
        if self.out is None or len(self.out) < total:
            grown = os.memfd_create("graphvision-arena", os.MFD_CLOEXEC)
            size = min(ARENA_BYTES, max(total, 2 * len(self.out or b"")))
            os.ftruncate(grown, size)
            if self.out is not None:
                self.out.close()
            self.out = mmap.mmap(grown, size)
        at = 0
        for i, raw in enumerate(raws):
            if ways[i] == _FILE:
                ways[i], offsets[i] = _ARENA, at
                self.out[at : at + raw.nbytes] = raw
                at += _padded(raw.nbytes)
        self.unanswered = True
        return ways, offsets, grown

    def receive(self) -> Any:
        """What the peer's :meth:`send` sent; shared arrays copied out, read-only, aligned."""
        head = self.connection.recv_bytes()
        self.unanswered = False  # the peer answers only once it has read all we sent
        count = int.from_bytes(head[:4], "little")
        ways = head[4 : 4 + count]
        grown = head[4 + count]
        start = 5 + count + 16 * count
        layout = np.frombuffer(head, np.int64, 2 * count, 5 + count).reshape(count, 2).tolist()
        buffers: list[Any] = [self.connection.recv_bytes() if w == _PIPE else None for w in ways]
        files = self._files(sum(w == _FILE for w in ways) + grown) if grown or _FILE in ways else []
        if grown:
            if self.into is not None:
                self.into.close()
            self.into = _mapped(files.pop(0))
        for i, way in enumerate(ways):
            if way == _ARENA:
                if self.into is None:
                    raise EOFError("shared arrays sent before their memory file")
                buffers[i] = _copied(self.into, *layout[i])
            elif way == _FILE:
                with _mapped(files.pop(0)) as file:
                    buffers[i] = _copied(file, 0, layout[i][1])
        return pickle.loads(memoryview(head)[start:], buffers=buffers)

    def _files(self, count: int) -> list[int]:
        carrier = _socket_of(self.connection)
        if carrier is None:
            raise EOFError("shared arrays sent over a connection that cannot carry them")
        try:
            data, files, _, _ = socket.recv_fds(carrier, 1, count)
        finally:
            carrier.close()
        if data != b"F" or len(files) != count:
            for file in files:
                os.close(file)
            raise EOFError("the sender ended while sending its shared arrays")
        return list(files)


def _padded(nbytes: int) -> int:
    """``nbytes`` rounded up to a multiple of the values' alignment."""
    return -(-nbytes // ALIGNMENT) * ALIGNMENT


def _memory_file(raw: memoryview) -> int:
    """A new memory file holding ``raw`` (written, not mapped: half the CPU)."""
    file = os.memfd_create("graphvision-value", os.MFD_CLOEXEC)
    view, written = raw.cast("B"), 0
    while written < raw.nbytes:
        written += os.write(file, view[written:])
    return file


def _mapped(file: int) -> mmap.mmap:
    """The memory file ``file`` mapped read-only (its descriptor closed)."""
    try:
        size = os.fstat(file).st_size
        return mmap.mmap(file, size, prot=mmap.PROT_READ)
    finally:
        os.close(file)


def _copied(source: mmap.mmap, offset: int, nbytes: int) -> memoryview:
    """``nbytes`` of ``source`` from ``offset`` in immutable memory, aligned."""

    def fill(window: memoryview) -> None:
        part = np.frombuffer(source, np.uint8, nbytes, offset)  # holds the map until deleted
        np.frombuffer(window, np.uint8)[:] = part
        del part

    return aligned_bytes(nbytes, fill)


def _socket_of(connection: Any) -> socket.socket | None:
    """A socket over a copy of the connection's descriptor; None if no socket or no memfd."""
    if not hasattr(os, "memfd_create"):  # Linux's: elsewhere every array takes the pipe
        return None
    copy = os.dup(connection.fileno())
    try:
        return socket.socket(fileno=copy)
    except OSError:
        os.close(copy)
        return None
