"""The bytes of a disk cache entry, and their checks (see :mod:`graphvision.cache.disk`).

::

    b"GVC3" | header length (8 bytes, little endian) | digest (16 bytes) | JSON header
            | zeros to a multiple of 64 bytes | payload

Every array in the payload starts at a multiple of 64 bytes plus the offset its value
had past a multiple of 64 when it was stored (its address modulo 64, a multiple of its
dtype's alignment: 0 for a copy the engine made, often 16 for an array NumPy or OpenCV
allocated and the engine froze where it lay), so arrays read back over a 64-byte aligned
buffer lie exactly as the computed values did, and a node reading one sees the same
layout cold and warm. (Entries written before the offsets were kept have them all 0,
and are read as they are.)
"""

from __future__ import annotations

import json
import struct
from collections.abc import Iterator
from typing import Any

import numpy as np
import xxhash

from graphvision.cache.entries import Encoded
from graphvision.values.memory import ALIGNMENT, alignment_offset, placed_offset

__all__ = ["MAGIC", "decode_blob", "encode_blob"]

MAGIC = b"GVC3"
_PREFIX = struct.Struct("<4sQ16s")  # magic, header length, digest of what follows


def _padded(offset: int) -> int:
    """``offset`` rounded up to a multiple of :data:`ALIGNMENT`."""
    return -(-offset // ALIGNMENT) * ALIGNMENT


def _shift(given: np.ndarray, stored: np.ndarray) -> int:
    """Where the stored array starts past a multiple of :data:`ALIGNMENT`: the offset the
    value had (when it is the value's own memory, aligned for its dtype), else 0."""
    if stored is not given:  # (a contiguous copy of a strided value)
        return 0
    return placed_offset(stored.dtype, alignment_offset(stored))


def encode_blob(entry: Encoded) -> Iterator[bytes | memoryview]:
    """The bytes of a disk entry for ``entry``, in chunks (arrays are not copied)."""
    specs: list[dict[str, Any]] = []
    chunks: list[bytes | memoryview] = []
    offset = 0
    arrays = {name: np.ascontiguousarray(a) for name, a in entry.arrays.items()}
    for name, array in arrays.items():
        if array.dtype.hasobject:
            raise TypeError(f"cannot cache object array '{name}'")
        start = _padded(offset) + _shift(entry.arrays[name], array)
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
    :data:`ALIGNMENT` (as :func:`~graphvision.values.memory.read_aligned` gives).
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


def _placeable(shift: int, nbytes: int, dtype: np.dtype) -> bool:
    """Whether an array of ``nbytes`` may start ``shift`` bytes past its 64-byte boundary."""
    return shift == (placed_offset(dtype, shift) if nbytes else 0)


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
        shift = offset - start  # past the multiple of 64: a multiple of the dtype's alignment
        if any(n < 0 for n in shape) or not _placeable(shift, nbytes, dtype):
            raise ValueError(f"array '{name}' has a bad shape or offset")
        start = offset
        if nbytes != int(np.prod(shape, dtype=np.int64)) * dtype.itemsize:
            raise ValueError(f"array '{name}': shape {list(shape)} disagrees with {nbytes} bytes")
        specs.append((name, dtype, shape, offset))
        expected_offset = start + nbytes
    if expected_offset != payload_bytes:
        raise ValueError(f"arrays add up to {expected_offset} bytes, payload is {payload_bytes}")
    return specs
