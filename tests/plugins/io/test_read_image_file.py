"""Reading an image file once (issue 26, item 1): a PNG, JPEG, BMP or WebP is opened once
with Pillow, and gives what ``imageio.v3.imread`` gives, to the bit, in dtype and shape, for
every mode and format graphvision reads; other files still go through imageio."""

from __future__ import annotations

import contextlib
import os
import re
import struct
import zlib
from collections.abc import Callable
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
from imageio.config import known_extensions
from PIL import Image, ImageCms, features

import graphvision as gv
from graphvision_plugins.io import read_array, read_file
from graphvision_plugins.io._image_file import PILLOW_SUFFIXES

RNG = np.random.default_rng(26)
GRAY = (RNG.random((9, 13)) * 255).astype(np.uint8)
RGB = (RNG.random((9, 13, 3)) * 255).astype(np.uint8)
RGBA = (RNG.random((9, 13, 4)) * 255).astype(np.uint8)
DEEP = (RNG.random((9, 13)) * 65535).astype(np.uint16)
SRGB = ImageCms.ImageCmsProfile(ImageCms.createProfile("sRGB")).tobytes()


def png(color_type: int, depth: int, width: int, rows: np.ndarray) -> bytes:
    """A PNG written chunk by chunk (Pillow writes no 16-bit RGB, 16-bit LA or 2-bit gray):
    ``rows`` holds each row's bytes (filter 0, big-endian samples)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        crc = struct.pack(">I", zlib.crc32(kind + data))
        return struct.pack(">I", len(data)) + kind + data + crc

    header = struct.pack(">IIBBBBB", width, len(rows), depth, color_type, 0, 0, 0)
    data = zlib.compress(b"".join(b"\0" + row.tobytes() for row in rows))
    signature = b"\x89PNG\r\n\x1a\n"
    return signature + chunk(b"IHDR", header) + chunk(b"IDAT", data) + chunk(b"IEND", b"")


def frames(mode: str) -> list[Image.Image]:
    return [Image.fromarray(RGB).convert(mode), Image.fromarray(RGB[::-1].copy()).convert(mode)]


def rotated() -> Image.Exif:
    exif = Image.Exif()
    exif[0x0112] = 6  # orientation: rotate 90° to show (imread applies it with rotate=True)
    return exif


def saved(image: Image.Image, **options: object) -> Callable[[Path], None]:
    return lambda path: image.save(path, **options)


def raw(data: bytes) -> Callable[[Path], None]:
    def write(path: Path) -> None:
        path.write_bytes(data)

    return write


gray, rgb, rgba = Image.fromarray(GRAY), Image.fromarray(RGB), Image.fromarray(RGBA)
FILES: dict[str, Callable[[Path], None]] = {
    "l.png": saved(gray),
    "rgb.png": saved(rgb),
    "rgba.png": saved(rgba),
    "la.png": saved(gray.convert("LA")),
    "p.png": saved(rgb.quantize(7)),
    "p_alpha.png": saved(rgba.quantize(5)),  # a palette with alpha: RGB, as imageio gives it
    "p_transparent.png": saved(rgb.quantize(7), transparency=2),
    "l_transparent.png": saved(gray, transparency=7),
    "i16.png": saved(Image.fromarray(DEEP)),
    "1.png": saved(gray.convert("1")),
    "rgb16.png": raw(png(2, 16, 13, np.dstack([DEEP] * 3).astype(">u2").reshape(9, -1))),
    "la16.png": raw(png(4, 16, 13, np.dstack([DEEP] * 2).astype(">u2").reshape(9, -1))),
    "l2.png": raw(png(0, 2, 12, np.packbits((GRAY[:, :12] >> 7).repeat(2, axis=1), axis=1))),
    "exif.png": saved(rgb, exif=rotated()),
    "named.jpg.png": saved(rgb),
    "png_named.jpg": saved(rgb, format="PNG"),
    "png_named.pbm": saved(gray, format="PNG"),  # imageio tries OpenCV first: RGB
    "png_named.tif": saved(gray, format="PNG"),
    "gif_named.png": saved(rgb.quantize(7), format="GIF"),  # imageio: a stack of one frame
    "l.jpg": saved(gray, quality=90),
    "rgb.jpg": saved(rgb, quality=90),
    "rgb_icc.jpg": saved(rgb, icc_profile=SRGB),
    "exif.jpeg": saved(rgb, exif=rotated()),
    "progressive.JPG": saved(rgb, progressive=True),
    "cmyk.jpg": saved(rgb.convert("CMYK"), quality=95),
    "mpo.jpg": saved(rgb, format="MPO", save_all=True, append_images=[rgb]),
    "l.bmp": saved(gray),
    "rgb.bmp": saved(rgb),
    "p.bmp": saved(rgb.quantize(7)),
    "1.bmp": saved(gray.convert("1")),
    "l.tif": saved(gray),
    "rgb.tif": saved(rgb),
    "p.tif": saved(rgb.quantize(7)),
    "i16.tif": saved(Image.fromarray(DEEP)),
    "cmyk.tif": saved(rgb.convert("CMYK")),
    "one.gif": saved(rgb.quantize(7)),
    "rgb.ppm": saved(rgb),
    "1.pbm": saved(gray.convert("1")),  # imageio reads .pbm with OpenCV, as RGB
}
if features.check("webp"):
    FILES |= {
        "rgb.webp": saved(rgb, lossless=True),
        "rgba.webp": saved(rgba, lossless=True),
        "lossy.webp": saved(rgb, quality=80),
    }
ONCE = {  # opened once with Pillow: imageio would read them with Pillow as they are
    *(name for name in FILES if Path(name).suffix.lower() in PILLOW_SUFFIXES),
} - {"mpo.jpg", "gif_named.png"}  # (imageio's plugin: MPO's first frame, GIF's stack)


def warned(name: str) -> contextlib.AbstractContextManager[object]:
    """Pillow's warning on expanding a palette whose alpha is bytes (imageio's too)."""
    if name != "p_alpha.png":
        return contextlib.nullcontext()
    return pytest.warns(UserWarning, match="Palette images with Transparency expressed in bytes")


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    made = tmp_path_factory.mktemp("modes")
    for name, write in FILES.items():
        write(made / name)
    return made


@pytest.mark.parametrize("name", sorted(FILES))
def test_a_file_reads_as_imageio_reads_it_to_the_bit(folder, name):
    path = folder / name
    if "cmyk" in name:  # reference: Pillow's device conversion, R = 255 - min(255, C + K)
        with Image.open(path) as image:
            expected = np.asarray(image.convert("RGB"))
    else:
        with warned(name):  # a photograph taken turned is read upright, as viewers show it
            expected = iio.imread(path, **({"rotate": True} if "exif" in name else {}))
    if "gif" in name:  # imageio reads a GIF as a stack of frames: a still one is its frame
        assert expected.shape[0] == 1 and expected.ndim == 4
        expected = expected[0]
    with warned(name):
        data = read_array(str(path))
    assert (data.dtype, data.shape) == (expected.dtype, expected.shape)
    assert data.tobytes() == expected.tobytes()
    assert data.flags.writeable or "cmyk" in name  # imageio's pixels are writeable


@pytest.mark.parametrize("name", sorted(ONCE))
def test_a_pillow_file_is_opened_once_and_imageio_not_used(folder, name, monkeypatch):
    opened = []
    open_image = Image.open
    monkeypatch.setattr(Image, "open", lambda *a, **k: opened.append(a) or open_image(*a, **k))
    for function in ("improps", "imread", "imopen"):
        monkeypatch.setattr(iio, function, lambda *a, **k: pytest.fail("imageio was used"))
    with warned(name):
        read_array(str(folder / name))
    assert len(opened) == 1


@pytest.mark.parametrize("name", sorted(ONCE))
def test_the_header_is_checked_against_the_budget_as_imageio_declares_it(folder, name, monkeypatch):
    declared = iio.improps(folder / name).shape  # the shape the imageio path checked
    pixels = declared[0] * declared[1]
    monkeypatch.setenv("GRAPHVISION_MAX_PIXELS", str(pixels - 1))
    monkeypatch.setattr(Image.Image, "load", lambda self: pytest.fail("decoded"))
    size = " × ".join(map(str, declared))
    with pytest.raises(gv.InputError, match=f"{name} declares {size} .* nothing was decoded"):
        read_array(str(folder / name))


def test_pillows_bomb_limit_is_lifted_only_while_reading(folder, monkeypatch):
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 10)  # 9 × 13 is over twice that: an error
    assert read_array(str(folder / "rgb.png")).shape == (9, 13, 3)
    assert Image.MAX_IMAGE_PIXELS == 10
    with pytest.raises(Image.DecompressionBombError), Image.open(folder / "rgb.png"):
        pass


def test_imageio_tries_pillow_first_for_the_suffixes_read_once():
    for suffix in PILLOW_SUFFIXES:  # the first plugin imageio.v3.imread tries for the suffix
        assert known_extensions[suffix][0].priority[0] == "pillow", suffix


def test_an_empty_truncated_or_unknown_file_says_so(folder, tmp_path):
    whole = (folder / "rgb.png").read_bytes()
    (tmp_path / "empty.png").write_bytes(b"")
    (tmp_path / "cut.png").write_bytes(whole[:60])
    jpeg = (folder / "rgb.jpg").read_bytes()
    assert len(jpeg) > 640  # its tables end before 600: the cut is in the pixel data
    (tmp_path / "cut.jpg").write_bytes(jpeg[:640])
    (tmp_path / "cut.tif").write_bytes(b"")
    (tmp_path / "text.png").write_text("not a png")
    (tmp_path / "notes.txt").write_text("not an image at all")
    for name, reason in (
        ("empty.png", r"\(the file is empty\)"),
        ("cut.tif", r"\(the file is empty\)"),
        ("cut.png", r"\(the file is truncated: its 60 bytes end before the image does\)"),
        ("cut.jpg", r"\(the file is truncated: its 640 bytes end before the image does\)"),
        ("text.png", r"\(neither Pillow nor imageio knows its format: save it as PNG, .*\)"),
        ("notes.txt", r"\(neither Pillow nor imageio knows its format: save it as PNG, .*\)"),
    ):
        with pytest.raises(ValueError, match=f"{name} is not a readable image {reason}$"):
            read_array(str(tmp_path / name))


def test_a_tiff_cut_in_its_pixels_says_it_is_truncated(tmp_path):
    """tifffile, which reads what Pillow does not, says "failed to read 4096 bytes, got
    ..." there: the reason in words, not the error's type."""
    pixels = np.random.default_rng(3).integers(0, 256, (64, 64), dtype=np.uint8)
    iio.imwrite(tmp_path / "whole.tif", pixels)
    whole = (tmp_path / "whole.tif").read_bytes()
    (tmp_path / "cut.tif").write_bytes(whole[: len(whole) // 2])
    size = f"{len(whole) // 2:,}"
    reason = rf"\(the file is truncated: its {size} bytes end before the image does\)$"
    with pytest.raises(ValueError, match=reason):
        read_array(str(tmp_path / "cut.tif"))


@pytest.mark.parametrize(
    "layout",
    [
        {"compression": "zlib"},
        {"compression": "zlib", "rowsperstrip": 8, "predictor": True},
        {"tile": (32, 32)},
        {"tile": (32, 32), "compression": "zlib"},
    ],
    ids=["zlib", "zlib-strips", "tiled", "tiled-zlib"],
)
def test_a_tiff_cut_in_compressed_strips_or_tiles_says_it_is_truncated(tmp_path, layout):
    """Cut inside zlib-compressed strips it said '(error)' (zlib's), inside tiles
    '(TiffFileError)': the file's strip and tile offsets say it was cut, whatever the codec."""
    import tifffile

    pixels = np.random.default_rng(4).integers(0, 256, (96, 96), dtype=np.uint8)
    tifffile.imwrite(tmp_path / "whole.tif", pixels, **layout)
    with tifffile.TiffFile(tmp_path / "whole.tif") as tiff:
        first = tiff.pages[0].dataoffsets[0]  # the tags lie before the pixels: kept whole
    whole = (tmp_path / "whole.tif").read_bytes()
    kept = (first + len(whole)) // 2
    (tmp_path / "cut.tif").write_bytes(whole[:kept])
    reason = rf"\(the file is truncated: its {kept:,} bytes end before the image does\)$"
    with pytest.raises(ValueError, match=reason):
        read_array(str(tmp_path / "cut.tif"))
    assert read_array(str(tmp_path / "whole.tif")).shape == (96, 96)  # whole, it reads


@pytest.mark.skipif(not Path("/proc/self/status").is_file(), reason="needs Linux's /proc")
@pytest.mark.parametrize("name", ["status.png", "status.tif", "status"])
def test_a_file_whose_size_reads_0_but_holds_bytes_is_not_called_empty(tmp_path, name):
    """A link to /proc/self/status (size 0, text inside) was 'the file is empty'."""
    (tmp_path / name).symlink_to("/proc/self/status")
    reason = r"\(its size reads 0 but it holds bytes, which are no image Pillow knows: .*\)$"
    with pytest.raises(ValueError, match=rf"{name} is not a readable image {reason}"):
        read_array(str(tmp_path / name))


HEADERS = [".png", ".jpg", ".bmp", ".gif", ".tif", *([".webp"] if features.check("webp") else [])]


@pytest.mark.parametrize("suffix", HEADERS)
@pytest.mark.parametrize("kept", [1, 4, 8, 12, 20, 30])
def test_a_file_cut_inside_its_header_says_it_is_truncated(tmp_path, suffix, kept):
    """The first bytes of an image file said '(SyntaxError)', '(IndexError)', '(error)'
    (the parsers' own errors, which name no cause); found by an earlier adversary."""
    whole = tmp_path / f"whole{suffix}"
    Image.fromarray(RGB).convert("P" if suffix == ".gif" else "RGB").save(whole)
    cut = tmp_path / f"cut{suffix}"
    cut.write_bytes(whole.read_bytes()[:kept])
    with pytest.raises(
        ValueError, match=rf"cut\{suffix} is not a readable image \(the file is trun"
    ):
        read_array(str(cut))


@pytest.mark.parametrize(
    ("suffix", "kept", "reason"),
    [
        (".png", 1, "not a complete PNG header (1 byte)"),
        (".png", 12, "not a complete PNG header (12 bytes)"),
        (".jpg", 4, "not a complete JPEG header (4 bytes)"),
        (".tif", 8, "not a complete TIFF header (8 bytes)"),
        (".gif", 30, "not a complete GIF header (30 bytes)"),
    ],
)
def test_a_header_cut_short_is_named_with_its_format(tmp_path, suffix, kept, reason):
    whole = tmp_path / f"whole{suffix}"
    Image.fromarray(RGB).convert("P" if suffix == ".gif" else "RGB").save(whole)
    cut = tmp_path / f"cut{suffix}"
    cut.write_bytes(whole.read_bytes()[:kept])
    with pytest.raises(ValueError, match=rf"\(the file is truncated: {re.escape(reason)}\)$"):
        read_array(str(cut))


def test_a_damaged_header_that_is_whole_is_not_called_truncated(tmp_path):
    """A PNG whose header chunk's checksum is wrong: the file is not short, it is damaged."""
    data = bytearray(png(2, 8, 13, RGB.reshape(9, -1)))
    data[29] ^= 0xFF  # in IHDR's CRC (8 bytes of signature, 8 of length and type, 13 of data)
    (tmp_path / "damaged.png").write_bytes(bytes(data))
    with pytest.raises(ValueError, match=r"damaged\.png is not a readable image") as refused:
        read_array(str(tmp_path / "damaged.png"))
    assert "truncated" not in str(refused.value)


ANIMATIONS = [".gif", ".png", ".tif", *([".webp"] if features.check("webp") else [])]


@pytest.mark.parametrize("suffix", ANIMATIONS)
def test_an_animation_or_a_multi_page_file_is_refused_before_it_is_decoded(tmp_path, suffix):
    """An animated GIF, PNG or WebP and a two-page TIFF; imageio would read the TIFF as a
    stack, which the input's port then refused for its shape, and the WebP as its first
    frame, without a word."""
    path = tmp_path / f"anim{suffix}"
    first, *rest = frames("P" if suffix == ".gif" else "RGB")
    first.save(path, save_all=True, append_images=rest)
    with pytest.raises(
        ValueError, match=f"anim{suffix} holds 2 frames .* save the frame you"
    ) as refused:
        read_array(str(path))
    # the call the message suggests gives a still image graphvision reads (a TIFF's
    # index=0 was its whole series: a file of two frames again)
    suggested = re.search(r"imageio\.v3\.imread\(path, (\w+)=0\)", str(refused.value))
    assert suggested is not None
    frame = tmp_path / "frame.png"
    iio.imwrite(frame, iio.imread(path, **{suggested[1]: 0}))
    assert read_array(str(frame)).shape == iio.imread(path, **{suggested[1]: 0}).shape[-3:]


def test_a_still_gif_runs_as_its_one_frame(tmp_path):
    """imageio reads a GIF as a stack; a still one used to be refused for its shape."""
    path = tmp_path / "still.gif"
    frames("P")[0].save(path)
    with Image.open(path) as image:
        expected = np.asarray(image.convert("RGB"), dtype=np.float32) / np.float32(255)
    assert np.array_equal(read_file(str(path)), expected)


@pytest.mark.parametrize("suffix", [".jpg", ".tif"])
def test_a_cmyk_profile_that_cannot_apply_is_refused_by_name(tmp_path, suffix):
    path = tmp_path / f"print{suffix}"
    rgb.convert("CMYK").save(path, icc_profile=SRGB)  # an RGB profile on CMYK data
    with pytest.raises(ValueError, match=f"print{suffix} is a CMYK image whose embedded colour"):
        read_array(str(path))


def test_readers_on_several_threads_put_pillows_limit_back(folder, monkeypatch):
    """Each reader saved and restored the one global alone: two threads interleaving left
    it lifted (None) for good. Every reader here starts before any ends."""
    import threading

    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 1234)
    inside, release = threading.Barrier(5), threading.Event()  # four readers and this thread
    decode = Image.Image.load

    waited: set[int] = set()

    def load(self: Image.Image) -> object:
        if threading.get_ident() not in waited:  # (Pillow may load more than once)
            waited.add(threading.get_ident())
            inside.wait(30)  # all four are reading now
            assert release.wait(30)
        return decode(self)

    monkeypatch.setattr(Image.Image, "load", load)
    readers = [
        threading.Thread(target=read_array, args=(str(folder / "rgb.png"),)) for _ in range(4)
    ]
    for reader in readers:
        reader.start()
    inside.wait(30)
    assert Image.MAX_IMAGE_PIXELS is None  # lifted while they read
    release.set()
    for reader in readers:
        reader.join(30)
    assert Image.MAX_IMAGE_PIXELS == 1234


def test_a_still_gif_counts_its_pixels_not_its_channels_against_the_budget(tmp_path, monkeypatch):
    """imageio declares a GIF as a stack (1, H, W, 3): its frame's H × W pixels count."""
    path = tmp_path / "still.gif"
    frames("P")[0].save(path)
    height, width = iio.imread(path).shape[1:3]
    monkeypatch.setenv("GRAPHVISION_MAX_PIXELS", str(height * width))
    assert read_array(str(path)).shape[:2] == (height, width)
    monkeypatch.setenv("GRAPHVISION_MAX_PIXELS", str(height * width - 1))
    with pytest.raises(gv.InputError, match=f"declares {height} × {width} "):
        read_array(str(path))


@pytest.mark.parametrize("suffix", [".png", ".webp", ".jpg"])
@pytest.mark.parametrize("orientation", range(1, 9))
def test_a_photograph_taken_turned_is_read_upright(tmp_path, suffix, orientation):
    # reference: Pillow's ImageOps.exif_transpose of the same file (what viewers show)
    from PIL import ImageOps

    exif = Image.Exif()
    exif[0x0112] = orientation  # EXIF Orientation
    path = tmp_path / f"turned{suffix}"
    Image.fromarray(RGB).save(path, exif=exif, **({"lossless": True} if suffix == ".webp" else {}))
    with Image.open(path) as image:
        upright = np.asarray(ImageOps.exif_transpose(image))
    read = read_array(str(path))
    assert read.shape == upright.shape == ((13, 9, 3) if orientation >= 5 else (9, 13, 3))
    np.testing.assert_array_equal(read, upright)
    assert read.flags.c_contiguous and read.flags.writeable


def test_a_png_whose_exif_follows_its_pixels_is_read_upright(tmp_path):
    # an eXIf chunk after IDAT: Pillow knows it only once the pixels are decoded
    exif = Image.Exif()
    exif[0x0112] = 6
    chunk_data = exif.tobytes()
    path = tmp_path / "late.png"
    Image.fromarray(GRAY).save(path)
    data = path.read_bytes()
    end = data.rindex(b"IEND") - 4
    chunk = struct.pack(">I", len(chunk_data)) + b"eXIf" + chunk_data
    chunk += struct.pack(">I", zlib.crc32(b"eXIf" + chunk_data))
    path.write_bytes(data[:end] + chunk + data[end:])
    np.testing.assert_array_equal(read_array(str(path)), np.rot90(GRAY, -1))


DAMAGED_EXIF = {"cut": b"Exif\x00\x00MM\x00*\x00\x00", "garbled": b"Exif\x00\x00" + b"\xff" * 30}


@pytest.mark.parametrize("suffix", [".png", ".webp", ".jpg"])
@pytest.mark.parametrize("block", DAMAGED_EXIF.values(), ids=DAMAGED_EXIF.keys())
def test_a_photograph_whose_exif_is_damaged_is_read_as_stored(tmp_path, suffix, block):
    # a cut or garbled EXIF block (Pillow's getexif raises on it): the pixels are whole
    path = tmp_path / f"damaged{suffix}"
    Image.fromarray(RGB).save(path, exif=block, **({"lossless": True} if suffix == ".webp" else {}))
    with Image.open(path) as image:
        stored = np.asarray(image)  # Pillow's pixels, not turned
    assert stored.shape == (9, 13, 3)
    np.testing.assert_array_equal(read_array(str(path)), stored)


def test_a_file_pillow_cannot_identify_is_read_by_imageio_as_stored(tmp_path, monkeypatch):
    # a format only imageio's other plugins read: Pillow's identification refused here
    path = tmp_path / "other.png"
    iio.imwrite(path, GRAY)

    def unidentified(*args, **kwargs):
        raise Image.UnidentifiedImageError("not identified")

    monkeypatch.setattr(Image, "open", unidentified)
    np.testing.assert_array_equal(read_array(str(path)), GRAY)


@pytest.mark.parametrize("suffix", [".png", ".jpg", ".bmp", ".webp"])
def test_a_file_read_whole_and_one_read_from_its_path_give_the_same_pixels(
    tmp_path: Path, suffix: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Files up to 64 MiB are read in one system call and parsed from memory; a larger one
    is still parsed from its path (nothing held twice): the pixels are imageio's either way."""
    from graphvision_plugins.io import _image_file

    path = tmp_path / f"image{suffix}"
    iio.imwrite(path, RGB)
    expected = iio.imread(path)
    whole = read_array(str(path))
    monkeypatch.setattr(_image_file, "_WHOLE", 0)  # every file "too large": its path
    assert isinstance(_image_file._contents(path), Path)
    from_path = read_array(str(path))
    for data in (whole, from_path):
        assert data.dtype == expected.dtype and np.array_equal(data, expected)


@pytest.mark.skipif(
    __import__("importlib").util.find_spec("imagecodecs") is not None,
    reason="imagecodecs installed: tifffile decodes LZW",
)
def test_a_compressed_tiff_tifffile_cannot_decode_names_the_package(tmp_path):
    """Pillow writes LZW, a common TIFF default; tifffile decodes it only with imagecodecs."""
    pixels = np.random.default_rng(4).integers(0, 256, (32, 48), dtype=np.uint8)
    Image.fromarray(pixels).save(tmp_path / "lzw.tiff", compression="tiff_lzw")
    with pytest.raises(ValueError, match=r"its compression, <COMPRESSION.LZW: 5>, .*imagecodecs"):
        read_array(str(tmp_path / "lzw.tiff"))


def test_what_is_not_a_regular_file_is_refused_by_name_after_one_stat(tmp_path: Path) -> None:
    (tmp_path / "folder.png").mkdir()
    (tmp_path / "a.png").write_bytes(b"")
    os.mkfifo(tmp_path / "pipe.png")
    with pytest.raises(IsADirectoryError, match=r"folder\.png is a folder, not an image file"):
        read_array(str(tmp_path / "folder.png"))
    for missing in ("nothing.png", "a.png/b.png", "nul\0.png"):  # (ENOENT, ENOTDIR, a NUL)
        with pytest.raises(FileNotFoundError, match="no such file: "):
            read_array(str(tmp_path / missing))
    with pytest.raises(ValueError, match=r"pipe\.png is not a regular file"):
        read_array(str(tmp_path / "pipe.png"))  # refused, not opened (it would block)
