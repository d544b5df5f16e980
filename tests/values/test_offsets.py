"""A value keeps its place modulo 64 bytes wherever it is materialised again.

A node's own array is frozen where it lies, whatever its address modulo 64 (NumPy's and
OpenCV's large arrays start 16 bytes past a multiple of 64), as long as it is aligned for
its dtype; a copy of it (read from the cache, received from another process) is placed at
the same offset, so a node reading it sees the same layout cold and warm.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from graphvision.values.memory import (
    alignment_offset,
    frozen_copies,
    frozen_copy,
    frozen_in_place,
)
from graphvision.values.ports import Placed, freeze_all, is_frozen

DTYPES = [np.bool_, np.uint8, np.int32, np.float32, np.float64, np.complex128]


def at(values: np.ndarray, offset: int) -> np.ndarray:
    """A writable copy of ``values`` whose data starts ``offset`` bytes past a multiple of 64."""
    buffer = np.empty(values.nbytes + 128, np.uint8)
    start = (offset - buffer.ctypes.data) % 64
    placed = buffer[start : start + values.nbytes].view(values.dtype).reshape(values.shape)
    placed[...] = values
    return placed


def offsets_of(dtype: type) -> range:
    return range(0, 64, np.dtype(dtype).alignment)


@pytest.mark.parametrize("dtype", DTYPES)
def test_a_copy_lies_at_the_offset_asked_for_with_the_same_bits(dtype):
    values = (np.random.default_rng(0).random((7, 9)) * 100).astype(dtype)
    for offset in offsets_of(dtype):
        copy = frozen_copy(at(values, 1 + offset % 7), offset)  # from anywhere
        assert alignment_offset(copy) == offset and copy.tobytes() == values.tobytes()
        assert is_frozen(copy) and not copy.flags.writeable
        strided = frozen_copy(at(values, 0)[:, ::2], offset)  # one pass from a strided view
        assert alignment_offset(strided) == offset and np.array_equal(strided, values[:, ::2])


def test_an_offset_the_dtype_cannot_lie_at_gives_a_copy_at_a_multiple_of_64():
    values = np.arange(10, dtype=np.float64)
    for offset in (3, 12, 64, -8):
        assert alignment_offset(frozen_copy(values, offset)) == 0


def test_a_tables_columns_keep_each_their_offset_in_one_buffer():
    rng = np.random.default_rng(1)
    columns = [rng.random(n).astype(d) for n, d in ((5, np.float32), (0, np.float64), (9, bool))]
    for shift in range(0, 64, 4):
        offsets = [shift, 8 * (shift // 8), (shift + 1) % 64]
        placed = [at(c, o) for c, o in zip(columns, offsets, strict=True)]
        copies = frozen_copies(placed, offsets)
        assert [alignment_offset(c) for c in copies] == [offsets[0], 0, offsets[2]]
        assert all(c.tobytes() == s.tobytes() for c, s in zip(copies, columns, strict=True))
        assert copies[0].base is not None and all(is_frozen(c) for c in copies)


def test_a_fresh_tables_columns_lie_at_multiples_of_64_over_zeroed_padding():
    """A node's own table (no offsets kept): each column at a multiple of 64 in one buffer of
    bytes, its shape kept (1-D and 2-D), read-only, and every other byte of the buffer 0."""
    columns = [
        np.arange(1, 6, dtype=np.int32),
        np.full((2, 3), 7.5),
        np.array([True, False, True]),
        np.ones(0, np.float32),
    ]
    for offsets in (None, [0, 0, 0, 0]):
        copies = frozen_copies(columns, offsets)
        assert [c.shape for c in copies] == [(5,), (2, 3), (3,), (0,)]
        for copy, column in zip(copies, columns, strict=True):
            assert copy.tobytes() == column.tobytes() and copy.dtype == column.dtype
        assert [alignment_offset(c) for c in copies[:3]] == [0, 0, 0]
        assert all(is_frozen(c) and not c.flags.writeable for c in copies)
        owner = copies[0].base
        assert isinstance(owner, bytes)
        first = copies[0].__array_interface__["data"][0]
        buffer = np.frombuffer(owner, np.uint8)
        start = first - buffer.__array_interface__["data"][0]
        laid = buffer[start : start + 64 * 3]  # 20 bytes, 48 and 3, each in 64: the rest is 0
        expected = np.zeros(64 * 3, np.uint8)
        for k, column in enumerate(columns[:3]):
            expected[64 * k : 64 * k + column.nbytes] = np.frombuffer(column.tobytes(), np.uint8)
        assert laid.tobytes() == expected.tobytes()
        outside = np.concatenate([buffer[:start], buffer[start + 64 * 3 :]])
        assert len(outside) == len(owner) - 64 * 3 and not outside.any()  # before and after


def test_columns_of_any_dtype_are_copied_bit_for_bit():
    """Each column's bytes as they are, whatever its dtype (no buffer format needed), for
    columns a node made as views (strided or reversed) too."""
    made = np.arange(12, dtype=np.int64).reshape(3, 4)
    columns = [
        np.array(["2020-01-01", "2021-02-03"], dtype="datetime64[D]"),
        np.array([(1, 2.5)], dtype=[("a", "<i2"), ("b", "<f8")]),
        np.array([1.5, -2.0], dtype=">f4"),
        np.array([1 + 2j], np.complex64),
        made[:, 1],
        made[0, ::-1],
        np.array(3.25),
    ]
    copies = frozen_copies(columns)
    for copy, column in zip(copies, columns, strict=True):
        assert copy.dtype == column.dtype and copy.shape == column.shape
        assert copy.tobytes() == column.tobytes() and copy.flags.c_contiguous
        assert is_frozen(copy) and alignment_offset(copy) == 0
    assert copies[4].tolist() == [1, 5, 9] and copies[5].tolist() == [3, 2, 1, 0]


@pytest.mark.parametrize("dtype", [np.bool_, np.int32, np.float32, np.float64])
def test_arrays_sent_to_another_process_are_frozen_there_at_their_offsets(dtype):
    """The transport (the arrays pickled as a process pool sends them) keeps each offset."""
    values = (np.random.default_rng(2).random((40, 30)) * 50).astype(dtype)
    for offset in offsets_of(dtype):
        sent = Placed.of({"a": frozen_copy(values, offset), "b": values[:3]})
        received = pickle.loads(pickle.dumps(sent, protocol=4))  # writable, anywhere
        frozen = freeze_all(received)
        assert alignment_offset(frozen["a"]) == offset and frozen["a"].tobytes() == values.tobytes()
        assert alignment_offset(frozen["b"]) == alignment_offset(values[:3])
        alone = freeze_all(Placed.of({"a": frozen_copy(values, offset)}))  # (one array: no table)
        assert alignment_offset(alone["a"]) == offset


def test_plain_arrays_received_are_frozen_at_a_multiple_of_64_as_before():
    received = pickle.loads(pickle.dumps({"a": np.arange(100.0), "b": np.arange(3)}))
    assert [alignment_offset(a) for a in freeze_all(received).values()] == [0, 0]


@pytest.mark.parametrize("offset", [0, 4, 16, 36, 60])
def test_a_nodes_own_array_is_frozen_where_it_lies_at_any_aligned_offset(offset):
    array = at(np.zeros((100, 100), np.float32), offset).copy()  # an owner, at malloc's place
    address = array.__array_interface__["data"][0]
    frozen = frozen_in_place(array)
    assert frozen is not None and frozen.__array_interface__["data"][0] == address
    view = at(np.ones((100, 100), np.float32), offset)  # a view whose owner only it holds
    address = view.__array_interface__["data"][0]
    frozen = frozen_in_place(view)
    assert frozen is not None and frozen.__array_interface__["data"][0] == address
    assert alignment_offset(frozen) == offset and is_frozen(frozen) and np.all(frozen == 1)
    with pytest.raises(ValueError, match="WRITEABLE"):
        frozen.flags.writeable = True


def test_a_view_is_not_frozen_in_place_while_its_owner_is_held_elsewhere():
    owner = np.zeros((100, 100), np.float32)
    assert frozen_in_place(owner[1:]) is None  # ``owner`` is held here: a copy is made

    def two_views() -> tuple[np.ndarray, np.ndarray]:
        other = np.zeros((100, 101), np.float32)
        return other[:, :3], other.reshape(-1)[: 100 * 100]

    kept, view = two_views()  # another view of the same owner is held
    assert frozen_in_place(view) is None
    del kept
    assert frozen_in_place(view) is not None  # (once it is not)
    small = np.zeros((1000, 100), np.float32)[:100]  # a tenth of an array nothing else holds
    assert frozen_in_place(small) is None  # copied: it would keep all of it alive
    unaligned = np.zeros(100 * 100 * 4 + 1, np.uint8)[1:].view(np.float32)
    assert frozen_in_place(unaligned) is None  # not aligned for its dtype: copied


@pytest.mark.parametrize("rows", [3, 40_000])  # under and over JOINED_BYTES in all
def test_large_and_small_values_are_copied_the_same_way(rows):
    """Joined in C (small) or part by part (large), the copies hold the same bytes at the same
    offsets, and every other byte of the buffer is 0."""
    from graphvision.values.memory import JOINED_BYTES

    rng = np.random.default_rng(3)
    columns = [rng.random(rows), rng.integers(0, 9, rows).astype(np.int16), np.ones(5, bool)]
    assert (sum(c.nbytes for c in columns) > JOINED_BYTES) == (rows > 3)
    for offsets in (None, [8, 2, 5]):
        copies = frozen_copies(columns, offsets)
        expected = offsets or [0, 0, 0]
        assert [alignment_offset(c) for c in copies] == expected
        assert all(c.tobytes() == s.tobytes() for c, s in zip(copies, columns, strict=True))
        buffer = np.frombuffer(copies[0].base, np.uint8).copy()
        base = np.frombuffer(copies[0].base, np.uint8).__array_interface__["data"][0]
        for copy in copies:
            at = copy.__array_interface__["data"][0] - base
            buffer[at : at + copy.nbytes] = 0
        assert not buffer.any()


def test_arrays_of_the_sizes_laid_out_before_are_copied_anew_each_time():
    """The layout of arrays of the same sizes (and offsets) is worked out once and reused: each
    call still copies its own values, at 64 bytes plus each offset, padding zeroed."""
    first = [np.arange(5, dtype=np.int32), np.array([1.5, 2.5]), np.ones((2, 3), np.int16)]
    second = [column * 3 for column in first]
    for offsets in (None, [4, 8, 0]):
        made = [frozen_copies(first, offsets), frozen_copies(second, offsets)]
        for copies, columns in zip(made, (first, second), strict=True):
            for index, (copy, column) in enumerate(zip(copies, columns, strict=True)):
                assert copy.shape == column.shape and copy.dtype == column.dtype
                assert copy.tolist() == column.tolist() and is_frozen(copy)
                assert alignment_offset(copy) == (offsets[index] if offsets else 0)
        assert made[1][0].tolist() == [0, 3, 6, 9, 12] and made[0][2].shape == (2, 3)
        owner = made[0][0].base
        assert isinstance(owner, bytes) and owner.count(0) >= len(owner) - 5 * 4 - 16 - 12


@pytest.mark.parametrize("shape", [(5, 5), (3,), (0,), (70_000,)])
def test_a_small_array_and_a_large_one_are_copied_to_their_bytes(shape):
    values = (np.arange(int(np.prod(shape))) % 7 > 2).reshape(shape)
    for offset in (0, 16):
        copy = frozen_copy(values, offset)
        assert copy.tobytes() == values.tobytes() and copy.shape == shape and is_frozen(copy)


def test_an_arrays_address_is_read_from_its_data_pointer_as_numpy_gives_it():
    """What :func:`frozen_in_place` takes for an array's address (its data pointer, read
    without asking NumPy for the buffer) is where NumPy says the data lies, for an owner and
    for views at an offset into theirs."""
    from graphvision.values.memory import _address_of

    owner = np.arange(4096, dtype=np.float64).reshape(64, 64)
    for array in (owner, owner[3:], owner.reshape(-1)[17:], at(owner, 36), owner.view(np.uint8)):
        assert _address_of(array) == array.__array_interface__["data"][0]
