"""One pixel budget for every image and array a run reads (issue 29, items 1 and 2): what a
file declares is checked before anything is decoded or inflated, and the budget is raised
with max_pixels / --max-pixels / GRAPHVISION_MAX_PIXELS."""

from __future__ import annotations

import io
import struct
import zipfile
import zlib
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
from numpy.lib import format as npy

import graphvision as gv
from graphvision.cli import main


def npy_header(shape: tuple[int, ...], dtype: str = "<f4") -> bytes:
    """The magic string and header of an .npy file declaring ``shape`` of ``dtype``."""
    stream = io.BytesIO()
    npy.write_array_header_1_0(stream, {"descr": dtype, "fortran_order": False, "shape": shape})
    return stream.getvalue()


def declaring_npz(path: Path, shape: tuple[int, ...]) -> Path:
    """An .npz whose one member declares ``shape`` float32 and holds 16 bytes (a zip bomb's
    header without its gigabytes: reading past the header would fail, not run out)."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("data.npy", npy_header(shape) + bytes(16))
    return path


def declaring_png(path: Path, width: int, height: int) -> Path:
    """A PNG whose header declares ``width`` × ``height`` gray pixels, with one row of data."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    idat = zlib.compress(bytes(width + 1))
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")
    )
    return path


def identity(kind: str) -> gv.Graph:
    graph = gv.Graph("identity")
    graph.input("value", kind)
    graph.output("value", "value")
    return graph


def test_an_npz_that_declares_too_much_is_refused_before_it_is_inflated(tmp_path):
    bomb = declaring_npz(tmp_path / "bomb.npz", (40_000, 40_000))
    with pytest.raises(gv.InputError) as caught:
        gv.run(identity("Array"), inputs={"value": str(bomb)}, cache=None)
    message = str(caught.value)
    assert f"{bomb} (array 'data') declares 40000 × 40000 (1,600.0 megapixels)" in message
    assert "over the pixel budget of 100.0 megapixels; nothing was decoded" in message
    assert "--max-pixels N" in message and "max_pixels=N" in message


def test_an_npy_and_an_image_that_declare_too_much_are_refused_by_name(tmp_path):
    array = tmp_path / "big.npy"
    array.write_bytes(npy_header((30_000, 30_000)) + bytes(16))
    image = declaring_png(tmp_path / "big.png", 21_000, 20_000)
    for path, kind, size in (
        (array, "Array", "30000 × 30000"),
        (image, "GrayImage", "20000 × 21000"),
    ):
        with pytest.raises(gv.InputError, match=f"declares {size}"):
            gv.run(identity(kind), inputs={"value": str(path)}, cache=None)


@pytest.mark.parametrize("suffix", [".png", ".npy", ".npz"])
def test_the_budget_is_one_knob_for_every_kind_of_file(tmp_path, suffix):
    """A 30 × 40 image is 1,200 pixels: refused at a budget of 1,000, read at 1,200."""
    picture = (np.arange(1200).reshape(30, 40) % 251).astype(np.uint8)
    path = tmp_path / f"small{suffix}"
    if suffix == ".png":
        iio.imwrite(path, picture)
    elif suffix == ".npy":
        np.save(path, picture.astype(np.float32) / 255)
    else:
        np.savez(path, data=picture.astype(np.float32) / 255)
    kind = "GrayImage" if suffix != ".npz" else "Array"
    refused = r"declares 30 × 40 \(1,200 pixels\), over the pixel budget of 1,000 pixels"
    with pytest.raises(gv.InputError, match=refused):
        gv.run(identity(kind), inputs={"value": str(path)}, cache=None, max_pixels=1000)
    result = gv.run(identity(kind), inputs={"value": str(path)}, cache=None, max_pixels=1200)
    assert result.outputs["value"].shape == (30, 40)


def test_an_rgb_image_counts_its_pixels_not_its_channels(tmp_path):
    path = tmp_path / "rgb.png"
    iio.imwrite(path, np.zeros((10, 10, 3), np.uint8))
    result = gv.run(identity("ColorImage"), inputs={"value": str(path)}, cache=None, max_pixels=100)
    assert result.outputs["value"].shape == (10, 10, 3)


def test_the_command_line_budget_reaches_the_readers(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("GRAPHVISION_MAX_PIXELS", "")  # unset (default) now, and after the test
    path = tmp_path / "small.png"
    iio.imwrite(path, np.zeros((30, 40), np.uint8))
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        "version: 1\nname: p\ninputs:\n  image: {type: GrayImage}\n"
        "nodes:\n  blur: {op: filters.gaussian, in: {image: image}}\noutputs:\n  blur: blur\n"
    )
    status = main(
        ["run", str(pipeline), "-i", f"image={path}", "--no-cache", "--max-pixels", "1000"]
    )
    err = capsys.readouterr().err
    assert status == 2 and "declares 30 × 40" in err and "Traceback" not in err
    assert (
        main(["run", str(pipeline), "-i", f"image={path}", "--no-cache", "--max-pixels", "2e3"])
        == 0
    )
    status = main(["run", str(pipeline), "--max-pixels", "many"])
    assert status == 2 and "not a whole number of pixels: 'many'" in capsys.readouterr().err


@pytest.mark.parametrize("text", ["lots", "-1", "0", "2.5"])
def test_a_malformed_budget_in_the_environment_is_named(monkeypatch, text):
    monkeypatch.setenv("GRAPHVISION_MAX_PIXELS", text)
    with pytest.raises(
        gv.InputError, match=f"GRAPHVISION_MAX_PIXELS='{text}' is not a whole number .* above 0"
    ):
        gv.max_pixels()
