"""Immutable buffers, and values that lie in the same place cold and warm.

Why both
--------
*Immutable*: a node must not change a value another node or the cache holds.
A ``writeable`` flag is not enough (``flags.writeable = True`` succeeds again
on an array that owns its memory); an array over a ``bytes`` object cannot be
made writable at all.

*Placed*: NumPy picks its loops by alignment. A float32 array at an address
that is not a multiple of 4 is "unaligned" and its reductions go through a
buffered loop that adds in another order, so the same value summed cold (as
computed) and warm (as read from the cache) gave 0.37982556 and 0.37982553;
element-wise work on it was 2.5x slower. Every value therefore lies at an
address aligned for its dtype, and at the same address modulo :data:`ALIGNMENT`
(64 bytes: a cache line, and the widest SIMD register) whether it was computed,
read from the cache or received from another process, so a node sees the same
memory layout either way and computes the same bits. A node's own array is kept
where it lies (:func:`frozen_in_place`; NumPy's and OpenCV's large arrays start
16 bytes past a multiple of 64, so requiring 64 had nearly every output copied:
2.8 MB per run of ``coins.yaml``, 0.47 MB since, the outputs of its node with
two); a copy is placed at the offset its value had (:func:`alignment_offset`,
kept in the disk cache's entries and sent with the arrays to another process),
else at a multiple of 64.

How
---
A ``bytes`` object is allocated ``ALIGNMENT`` bytes (plus the offset asked for)
larger than needed and filled exactly once, right after it is made and before
anything else can see it, through a ``ctypes`` window at the first aligned
address inside it (plus that offset). What
callers keep is a read-only ``memoryview`` of that window. The object is made
uninitialised (``PyBytes_FromStringAndSize(NULL, n)``, as CPython itself makes
one it is about to fill): zeroing it first was a third of the cost of freezing
a 1.4 MB image, for bytes overwritten at once (the padding around the window is
never read).
"""

from __future__ import annotations

import ctypes
import sys
import weakref
from collections.abc import Callable
from functools import partial
from itertools import repeat
from operator import attrgetter
from typing import Any, BinaryIO

import numpy as np

__all__ = [
    "ALIGNMENT",
    "aligned_bytes",
    "alignment_offset",
    "frozen_copies",
    "frozen_copy",
    "frozen_in_place",
    "is_aligned",
    "is_frozen_window",
    "placed_offset",
    "read_aligned",
]

ALIGNMENT = 64

_new_bytes = ctypes.pythonapi.PyBytes_FromStringAndSize
_new_bytes.restype = ctypes.py_object
_new_bytes.argtypes = (ctypes.c_void_p, ctypes.c_ssize_t)


def _data_offset() -> int:
    probe = b"graphvision"  # where a bytes object's data starts from its address (id)
    return (ctypes.cast(ctypes.c_char_p(probe), ctypes.c_void_p).value or 0) - id(probe)


_DATA_OFFSET = _data_offset()


def aligned_bytes(nbytes: int, fill: Callable[[memoryview], None]) -> memoryview:
    """``nbytes`` of immutable memory at a multiple of :data:`ALIGNMENT`, filled once by ``fill``.

    Parameters
    ----------
    nbytes : int
        Size of the buffer.
    fill : callable
        Called once with a writable ``memoryview`` of the buffer (format ``B``);
        it must write all of it and keep no reference to it.

    Returns
    -------
    memoryview
        Read-only, over a ``bytes`` object no one else holds.
    """
    # a new object (sizes of 2 bytes and more are never shared), filled below
    owner: bytes = _new_bytes(None, nbytes + ALIGNMENT)
    start = ctypes.cast(ctypes.c_char_p(owner), ctypes.c_void_p).value or 0
    offset = -start % ALIGNMENT
    if nbytes:
        window = (ctypes.c_char * nbytes).from_address(start + offset)
        fill(memoryview(window).cast("B"))
    return memoryview(owner)[offset : offset + nbytes]


def _new_aligned(nbytes: int, shift: int = 0) -> tuple[bytes, int, int]:
    """A new uninitialised ``bytes`` object of ``nbytes`` and the padding, with the
    address and the offset of its first aligned byte (to be written once, at once);
    ``shift`` more bytes of padding after that byte, for a value placed there."""
    owner: bytes = _new_bytes(None, nbytes + ALIGNMENT + shift)
    start = id(owner) + _DATA_OFFSET  # (the address ctypes.c_char_p(owner) gives)
    return owner, start, -start % ALIGNMENT


def alignment_offset(array: np.ndarray) -> int:
    """Where ``array``'s data starts past a multiple of :data:`ALIGNMENT` (its address
    modulo 64; 0 for an empty array): what a copy of it keeps to lie as it did."""
    if not array.size:
        return 0
    return int(array.__array_interface__["data"][0] % ALIGNMENT)


def placed_offset(dtype: np.dtype, offset: int) -> int:
    """``offset`` (bytes past a multiple of :data:`ALIGNMENT`) if an array of ``dtype`` can
    lie there, else 0."""
    if 0 < offset < ALIGNMENT and offset % dtype.alignment == 0:
        return offset
    return 0


def frozen_copy(array: np.ndarray, offset: int = 0) -> np.ndarray:
    """A copy of ``array`` in an immutable buffer (C order, same dtype and shape), at an
    address ``offset`` bytes past a multiple of :data:`ALIGNMENT` (where the value lay when
    it was computed; 0 unless given, and 0 for an offset the dtype cannot lie at)."""
    dtype, shape = array.dtype, array.shape
    shift = placed_offset(dtype, offset)
    owner, start, first = _new_aligned(array.nbytes, shift)
    first += shift
    if not array.flags.c_contiguous:  # one pass from the strided array into the window
        if array.nbytes:
            window = (ctypes.c_char * array.nbytes).from_address(start + first)
            target = np.frombuffer(memoryview(window).cast("B"), dtype).reshape(shape)
            np.copyto(target, array, casting="no")
            del target, window
    elif array.nbytes > JOINED_BYTES:
        _fill(start + first, array)
    elif array.nbytes:  # (a small one: its bytes and one memmove, a window less to make)
        ctypes.memmove(start + first, array.tobytes(), array.nbytes)
    return _view(owner, dtype, array.size, first, shape)


def _view(owner: bytes, dtype: np.dtype, size: int, at: int, shape: tuple[int, ...]) -> np.ndarray:
    """The array of ``shape`` at byte ``at`` of ``owner`` (a 1-D one without a reshape: a
    view less per table column)."""
    flat = np.frombuffer(owner, dtype, size, at)
    return flat if len(shape) == 1 else flat.reshape(shape)


def _fill(address: int, array: np.ndarray) -> None:
    """Copy the C-contiguous ``array`` to ``address``."""
    window = memoryview((ctypes.c_char * array.nbytes).from_address(address)).cast("B")
    with window:
        _copy(window, 0, array, address)


def _copy(window: memoryview, begin: int, array: np.ndarray, address: int) -> None:
    """Copy the C-contiguous ``array`` into ``window`` (at ``address``) from byte ``begin``:
    through a memoryview where NumPy exports the dtype as a buffer (a microsecond or more
    less per array than ``ctypes.memmove``, which needs the address that
    ``__array_interface__`` builds a dict for: most of freezing a table's small columns),
    else through ``ctypes.memmove``."""
    try:
        window[begin : begin + array.nbytes] = memoryview(array).cast("B")  # type: ignore[arg-type]
    except (TypeError, ValueError, NotImplementedError):  # a dtype with no buffer format
        source = array.__array_interface__["data"][0]
        ctypes.memmove(address + begin, source, array.nbytes)


IN_PLACE_BYTES = 16384
"""Arrays smaller than this are copied: a copy costs no more than freezing in place."""

_from_memory = ctypes.pythonapi.PyMemoryView_FromMemory
_from_memory.restype = ctypes.py_object
_from_memory.argtypes = (ctypes.c_void_p, ctypes.c_ssize_t, ctypes.c_int)
_READ_ONLY = 0x100  # PyBUF_READ

_KEPT: dict[int, tuple[np.ndarray, weakref.ref[memoryview]]] = {}
"""The arrays :func:`frozen_in_place` froze, by the ``id`` of the read-only window every view
of them rests on: each is kept alive by its window, and only by it."""


def _release(key: int, ref: weakref.ref[memoryview]) -> None:
    entry = _KEPT.get(key)
    if entry is not None and entry[1] is ref:  # (not a newer window at the same address)
        del _KEPT[key]


def frozen_in_place(array: np.ndarray) -> np.ndarray | None:
    """``array``'s own memory, made immutable without a copy, when it can be (else None).

    For an array that a node has just returned and that nothing but the caller holds (the
    caller checks that: ``sys.getrefcount``): a plain C-ordered ``ndarray`` aligned for its
    dtype that owns its memory, or a view of one (``reshape`` of a result) that nothing
    but the view holds and that covers at least 7/8 of its memory. Its ``writeable``
    flag (and its owner's) is cleared and what the caller keeps is a view through a
    read-only ``memoryview`` over that memory that refers to no object
    (``PyMemoryView_FromMemory``): the array is no base of the view and the window does
    not name it, so no flag set on the view or anything it refers to makes it writable,
    as with a copy in ``bytes``; the array is kept alive by the window (held by every
    view of it) and freed with it. The copy (0.8 ms of a 12 ms pipeline's
    run for 3.3 MB of images) is saved.

    The value stays at its address, whatever it is modulo :data:`ALIGNMENT` (NumPy's and
    OpenCV's large arrays start 16 bytes past a multiple of 64): where the value is
    materialised again (read from the cache, received from another process), it is
    placed at the same offset modulo 64 (:func:`alignment_offset`), so a node reading
    it sees the same layout cold and warm.
    """
    flags = array.flags
    if (
        type(array) is not np.ndarray
        or not (flags.writeable and flags.c_contiguous and flags.aligned)
        or array.nbytes < IN_PLACE_BYTES
        or array.dtype.hasobject
    ):
        return None
    owner = array.base  # a view: of an array owning its memory that only the view holds,
    if owner is not None and not (  # most of whose memory it covers (a small slice of a
        type(owner) is np.ndarray  # large array is copied: it would keep all of it alive)
        and owner.base is None
        and owner.flags.writeable
        and sys.getrefcount(owner) <= _VIEW_ONLY_REFS
        and 8 * array.nbytes >= 7 * owner.nbytes
    ):
        return None
    address = _address_of(array)
    flags.writeable = False  # (an array over the window at once: no 1-D one to reshape)
    frozen = np.ndarray(array.shape, array.dtype, _from_memory(address, array.nbytes, _READ_ONLY))
    window = frozen.base  # the memoryview numpy holds (every view of ``frozen`` rests on it)
    if not isinstance(window, memoryview):  # (not how numpy holds a buffer: copy instead)
        flags.writeable = True
        return None
    if owner is not None:
        owner.flags.writeable = False
    key = id(window)
    _KEPT[key] = (array, weakref.ref(window, partial(_release, key)))  # (no frame more)
    return frozen


def _array_data_offset() -> int | None:
    """Where an array's data pointer lies from its ``id`` (after the object's header, as
    NumPy's ABI's ``PyArray_DATA`` reads it), found on a probe; None when not there."""
    probe, offset = np.arange(3.0), object.__basicsize__
    found = ctypes.c_void_p.from_address(id(probe) + offset).value
    return offset if found == probe.__array_interface__["data"][0] else None


_ARRAY_DATA, _pointer_at = _array_data_offset(), ctypes.c_void_p.from_address


def _address_of(array: np.ndarray) -> int:
    """The address of a live ``array``'s data: its data pointer, read where
    :func:`_array_data_offset` found it, without asking NumPy for the buffer (a format
    string and a buffer record: 2 µs an array once a script's calls left that code cold),
    else through a one-byte ``ctypes`` window on its buffer, released at once."""
    if _ARRAY_DATA is not None:
        return _pointer_at(id(array) + _ARRAY_DATA).value or 0
    return ctypes.addressof(ctypes.c_char.from_buffer(array))  # type: ignore[arg-type]


_VIEW_ONLY_REFS = 3 if sys.version_info < (3, 14) else -(2**20)
"""References to a view's owner in :func:`frozen_in_place` held by the view alone (its ``base``,
``owner``, ``getrefcount``'s argument; on 3.14, which counts the stack otherwise, no view is)."""


def is_frozen_window(window: memoryview) -> bool:
    """Whether ``window`` is the read-only window of an array :func:`frozen_in_place` froze."""
    entry = _KEPT.get(id(window))
    return entry is not None and entry[1]() is window


def frozen_copies(arrays: list[np.ndarray], offsets: list[int] | None = None) -> list[np.ndarray]:
    """Copies of ``arrays`` in one immutable buffer (C order, same dtypes and shapes), each
    at a multiple of :data:`ALIGNMENT` plus its entry of ``offsets`` (where it lay when it
    was computed; 0 when not given): a value of many arrays (a table's columns) is frozen
    with one buffer instead of one each.

    The buffer's bytes (the arrays, the zeroed padding between them, before the first and
    after the last) are joined in C (``bytes.join``) and copied into it with one
    ``memmove``: a table of 17 small columns froze in 10 µs instead of 37, where a window
    slice per array and its padding was most. Where each array goes depends only on the
    arrays' sizes (and offsets and dtypes, when offsets are given), the same for every run
    of a graph on one image: it is worked out once for them (:func:`_layout`), and the
    steps per array left (making it contiguous, its size, its view of the buffer) are
    ``map`` calls, with no Python step per array (17 columns: 23 µs before, 13 since).
    """
    sources = list(map(np.ascontiguousarray, arrays))
    sizes = tuple(map(_NBYTES, sources))
    shifts = offsets if offsets and any(offsets) else None  # (none: a node's fresh table)
    placed = tuple(map(placed_offset, map(_DTYPE, sources), shifts)) if shifts else ()
    starts, gaps, total = _layout(sizes, placed)
    owner, start, first = _new_aligned(total)
    count = len(sources)
    parts: list[Any] = [b""] * (2 * count + 3)
    parts[0], parts[-1] = _PADS[first], _PADS[ALIGNMENT - first]  # every byte written
    parts[1::2] = gaps
    parts[2 : 2 * count + 1 : 2] = sources
    _write(start, parts, ALIGNMENT + total)
    views = list(
        map(
            np.frombuffer,
            repeat(owner, count),
            map(_DTYPE, arrays),
            map(_SIZE, arrays),
            map(first.__add__, starts),
        )
    )
    if any(map((1).__ne__, map(_NDIM, arrays))):  # (0-d, 2-d...: their own shapes)
        views = [
            flat if array.ndim == 1 else flat.reshape(array.shape)
            for flat, array in zip(views, arrays, strict=True)
        ]
    return views


_NBYTES, _DTYPE, _SIZE, _NDIM = map(attrgetter, ("nbytes", "dtype", "size", "ndim"))
_PADS = [bytes(size) for size in range(ALIGNMENT + 1)]  # (each padding made once)
_Layout = tuple[list[int], list[bytes], int]
_LAYOUTS: dict[tuple[tuple[int, ...], tuple[int, ...]], _Layout] = {}


def _layout(sizes: tuple[int, ...], shifts: tuple[int, ...]) -> _Layout:
    """Where arrays of ``sizes`` bytes go in one buffer, each at a multiple of
    :data:`ALIGNMENT` plus its entry of ``shifts`` (none: 0): each one's start, the zeroed
    bytes before each one and after the last, and the buffer's size (a multiple of
    :data:`ALIGNMENT`). Kept for the last sizes and shifts asked for."""
    known = _LAYOUTS.get((sizes, shifts))
    if known is not None:
        return known
    starts, gaps, total, end = [], [], 0, 0
    for index, size in enumerate(sizes):
        begin = total + (shifts[index] if shifts else 0)
        starts.append(begin)
        gaps.append(bytes(begin - end))
        end = begin + size
        total = -(-end // ALIGNMENT) * ALIGNMENT  # (rounded up)
    gaps.append(bytes(total - end))
    if len(_LAYOUTS) > 64:
        _LAYOUTS.clear()
    known = _LAYOUTS[(sizes, shifts)] = (starts, gaps, total)
    return known


JOINED_BYTES = 65536
"""Up to this many bytes, :func:`frozen_copies` joins its parts in C and copies them at once
(one step per array); above it each part is copied where it goes (no second copy of the
whole: a 0.5 MB array's took 0.37 ms, a temporary buffer of new pages each time)."""


def _write(address: int, parts: list[Any], size: int) -> None:
    """Copy ``parts`` (C-contiguous arrays and ``bytes``), one after the other, to the
    ``size`` bytes at ``address``."""
    if size <= JOINED_BYTES:
        ctypes.memmove(address, b"".join(parts), size)
        return
    window = memoryview((ctypes.c_char * size).from_address(address)).cast("B")
    with window:
        at = 0
        for part in parts:
            if type(part) is bytes:
                window[at : at + len(part)] = part
                at += len(part)
            else:
                _copy(window, at, part, address)
                at += part.nbytes


def is_aligned(array: np.ndarray) -> bool:
    """Whether ``array``'s data starts at a multiple of :data:`ALIGNMENT` (or it is empty)."""
    return array.size == 0 or array.ctypes.data % ALIGNMENT == 0


def read_aligned(stream: BinaryIO, nbytes: int) -> memoryview:
    """The next ``nbytes`` of ``stream`` in an immutable aligned buffer.

    Raises
    ------
    EOFError
        When the stream ends first (a file cut short while it was being read).
    """

    def fill(window: memoryview) -> None:
        done = 0
        while done < nbytes:
            got = stream.readinto(window[done:])  # type: ignore[attr-defined]  # files have it
            if not got:
                raise EOFError(f"ended after {done} of {nbytes} bytes")
            done += got

    return aligned_bytes(nbytes, fill)
