"""How values cross between the studio's server and its worker processes: pickled with
their arrays out of band (protocol 5), each array's bytes written once, through the pipe
or, from ``SHARED_BYTES`` up, in a memory file whose descriptor crosses the socket
(Linux's ``memfd_create``; elsewhere every array takes the pipe). A received shared array
is a read-only view of its memory file."""

from __future__ import annotations

import mmap
import os
import pickle
import socket
from typing import Any

__all__ = ["SHARED_BYTES", "receive", "send"]

SHARED_BYTES = 1 << 20  # an array this large travels in shared memory, not through the socket


def send(connection: Any, message: Any) -> None:
    """Send ``message`` with its arrays out of band (pickle protocol 5), each written once:
    through the pipe, or (SHARED_BYTES or more) into a memory file whose descriptor crosses
    the socket (6 MB through the socket took the two processes ~60 wake-ups by turns)."""
    buffers: list[pickle.PickleBuffer] = []
    head = pickle.dumps(message, protocol=5, buffer_callback=buffers.append)
    raws = [buffer.raw() for buffer in buffers]
    carrier = _socket_of(connection) if any(r.nbytes >= SHARED_BYTES for r in raws) else None
    shared = [carrier is not None and r.nbytes >= SHARED_BYTES for r in raws]
    connection.send_bytes(len(raws).to_bytes(4, "little") + bytes(shared) + head)
    files = []
    try:
        for raw, in_file in zip(raws, shared, strict=True):
            if in_file:
                files.append(os.memfd_create("graphvision-value", os.MFD_CLOEXEC))
                os.ftruncate(files[-1], raw.nbytes)
                with mmap.mmap(files[-1], raw.nbytes) as mapped:
                    mapped[:] = raw
            else:
                connection.send_bytes(raw)
        if carrier is not None:
            socket.send_fds(carrier, [b"F"], files)
    finally:
        for file in files:
            os.close(file)
        if carrier is not None:
            carrier.close()


def receive(connection: Any) -> Any:
    """What :func:`send` sent (its shared arrays read-only, over the memory files)."""
    head = connection.recv_bytes()
    count = int.from_bytes(head[:4], "little")
    shared = head[4 : 4 + count]
    buffers: list[Any] = [None if s else connection.recv_bytes() for s in shared]
    if any(shared):
        carrier = _socket_of(connection)
        assert carrier is not None  # the sender used it: it is a socket
        try:
            data, files, _, _ = socket.recv_fds(carrier, 1, len(buffers))
        finally:
            carrier.close()
        mapped: list[Any] = []
        for file in files:
            try:
                size = os.fstat(file).st_size
                mapped.append(mmap.mmap(file, size, prot=mmap.PROT_READ) if size else b"")
            finally:
                os.close(file)
        if data != b"F" or len(mapped) != sum(shared):
            raise EOFError("the sender ended while sending its shared arrays")
        kept = iter(mapped)
        buffers = [next(kept) if s else b for s, b in zip(shared, buffers, strict=True)]
    return pickle.loads(memoryview(head)[4 + count :], buffers=buffers)


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
