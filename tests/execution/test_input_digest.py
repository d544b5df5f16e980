"""A run's input file in its provenance: the SHA-256 of the bytes the reader read, hashed as
it read them (the file is not opened again to hash it), and its path resolved as
``Path.resolve`` resolves it, through linked folders and linked files."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import graphvision as gv
from graphvision.execution import provenance


def _graph() -> gv.Graph:
    graph = gv.Graph("same")
    graph.input("image", "Image")
    graph.output("image", "image")
    return graph


def _png(path: Path, seed: int = 0) -> Path:
    pixels = (np.random.default_rng(seed).random((7, 9)) * 255).astype(np.uint8)
    iio.imwrite(path, pixels)
    return path


def test_the_digest_is_of_the_bytes_read_and_the_file_is_not_read_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    image = _png(tmp_path / "a.png")
    hashed: list[str] = []
    original = provenance.file_sha256
    monkeypatch.setattr(provenance, "file_sha256", lambda p: hashed.append(p) or original(p))
    described = gv.run(_graph(), inputs={"image": str(image)}).record.inputs["image"]
    assert described["sha256"] == hashlib.sha256(image.read_bytes()).hexdigest()
    assert described["path"] == str(image.resolve())
    assert hashed == []  # from the reader's bytes
    _png(tmp_path / "b.png", seed=1)
    os.replace(tmp_path / "b.png", image)  # another file under the same name
    again = gv.run(_graph(), inputs={"image": str(image)}).record.inputs["image"]
    assert again["sha256"] == hashlib.sha256(image.read_bytes()).hexdigest()
    assert again["sha256"] != described["sha256"]


def test_an_input_read_elsewhere_is_hashed_from_its_file(tmp_path: Path) -> None:
    """A TIFF is read by tifffile from its path: the provenance hashes the file itself."""
    image = tmp_path / "a.tif"
    iio.imwrite(image, (np.arange(12, dtype=np.uint8) * 20).reshape(3, 4))
    described = gv.run(_graph(), inputs={"image": str(image)}).record.inputs["image"]
    assert described["sha256"] == hashlib.sha256(image.read_bytes()).hexdigest()


def test_the_path_is_resolved_through_linked_folders_and_linked_files(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    real = tmp_path / "real"
    real.mkdir()
    image = _png(real / "a.png")
    (tmp_path / "folder").symlink_to(real)
    (tmp_path / "file.png").symlink_to(image)
    (tmp_path / "other").mkdir()
    monkeypatch.chdir(tmp_path / "other")
    given = [
        str(tmp_path / "folder" / "a.png"),  # a linked folder
        str(tmp_path / "file.png"),  # a linked file
        "../folder/a.png",  # relative, through the link, then up
        "../real/./a.png",
    ]
    for path in given:
        described = gv.run(_graph(), inputs={"image": path}).record.inputs["image"]
        assert described["given"] == path
        assert described["path"] == os.path.realpath(path) == str(image.resolve())
    (tmp_path / "folder").unlink()
    (tmp_path / "folder").symlink_to(tmp_path / "moved")
    (real).rename(tmp_path / "moved")  # the link retargeted: resolved again
    described = gv.run(_graph(), inputs={"image": given[0]}).record.inputs["image"]
    assert described["path"] == str(tmp_path / "moved" / "a.png")
