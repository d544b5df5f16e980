"""An input file read whole once, its SHA-256 and resolved path kept for the run's provenance
(:mod:`graphvision.values.file_bytes`): the digest is the bytes' (FIPS 180-2's own example
values), kept by the path and the file's stamp, forgotten for a file changed since."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import graphvision as gv
from graphvision.values.file_bytes import read_before

ABC = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"  # FIPS 180-2, B.1
EMPTY = "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"  # SHA-256 of b""


def test_the_bytes_read_and_their_sha256_kept_by_the_files_stamp(tmp_path: Path) -> None:
    file = tmp_path / "abc.txt"
    file.write_bytes(b"abc")
    assert gv.read_file_bytes(file) == b"abc"
    digest, where = read_before(file, os.stat(file))
    assert digest == ABC
    named = os.path.isdir("/proc/self/fd")  # (Linux: the kernel names an open file's path)
    assert where == (str(file.resolve()) if named else None)
    assert read_before(str(file), os.stat(file)) == (digest, where)
    assert read_before(tmp_path / "." / "abc.txt", os.stat(file)) == (digest, where)
    empty = tmp_path / "empty"
    empty.write_bytes(b"")
    assert gv.read_file_bytes(str(empty)) == b""
    assert read_before(empty, os.stat(empty)) == (EMPTY, str(empty.resolve()) if named else None)


def test_a_file_over_the_limit_is_not_read_nor_hashed(tmp_path: Path) -> None:
    file = tmp_path / "big.bin"
    file.write_bytes(b"x" * 100)
    assert gv.read_file_bytes(file, limit=99) is None
    assert read_before(file, os.stat(file)) is None
    assert gv.read_file_bytes(file, limit=100) == b"x" * 100  # the limit is inclusive


def test_a_file_changed_since_it_was_read_has_no_digest_kept(tmp_path: Path) -> None:
    file = tmp_path / "a.txt"
    file.write_bytes(b"abc")
    gv.read_file_bytes(file)
    file.write_bytes(b"abcd")  # another size: another stamp
    assert read_before(file, os.stat(file)) is None
    replaced = tmp_path / "b.txt"
    replaced.write_bytes(b"abc")
    os.replace(replaced, file)  # another inode
    assert read_before(file, os.stat(file)) is None


def test_a_missing_file_is_refused_as_open_refuses_it(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError) as caught:
        gv.read_file_bytes(tmp_path / "nothing.png")
    assert caught.value.filename == str(tmp_path / "nothing.png")


def test_a_file_read_again_unchanged_is_hashed_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from graphvision.values import file_bytes

    hashed: list[int] = []
    sha256 = file_bytes.hashlib.sha256

    class Counted:
        @staticmethod
        def sha256(data: bytes) -> object:
            hashed.append(len(data))
            return sha256(data)

    monkeypatch.setattr(file_bytes, "hashlib", Counted)
    file = tmp_path / "a.txt"
    file.write_bytes(b"abc")
    for _ in range(3):
        assert gv.read_file_bytes(file) == b"abc"
    assert hashed == [3]
    file.write_bytes(b"abcd")  # changed: hashed again
    assert gv.read_file_bytes(file) == b"abcd"
    assert hashed == [3, 4]
    assert read_before(file, os.stat(file))[0] == sha256(b"abcd").hexdigest()
