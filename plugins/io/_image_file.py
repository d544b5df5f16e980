"""Decoding an image file: one Pillow handle where imageio would read it with Pillow.

``imageio.v3.imread`` picks its plugin by the file's suffix: Pillow first for
PNG, JPEG, BMP and WebP, tifffile for TIFF. Its Pillow plugin then returns
``np.asarray(image)``, after expanding a palette (``image.convert(image.palette.mode)``).
Reading a file through imageio opened it three times (``improps`` for the
header, Pillow again for the CMYK check, ``imread`` to decode) and paid the
plugin's start each time (a failed ``import pillow_heif``, a search of
``sys.path``). For those suffixes, formats and modes graphvision reads the
file once (whole, in one system call: :func:`_contents`) and opens it once
with Pillow: the header gives the size, checked against the pixel budget
before a byte is decoded, the mode tells a CMYK image, and the same handle
decodes, with the pixels, dtype and shape ``imread`` gives.

Everything else goes through imageio as before, with the same handle for
the CMYK check: TIFF (read by tifffile), GIF and APNG (read as a stack of
frames, refused when there are several), the modes imageio's plugin
converts otherwise (a 32-bit ``I`` PNG) or that it keeps as they are but
graphvision never saw through this path (``F``, ``YCbCr``, ...), MPO, and
any file Pillow cannot identify.
"""

from __future__ import annotations

import contextlib
import io
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from graphvision import InputError, check_pixels, read_file_bytes

if TYPE_CHECKING:
    from PIL.Image import Image as PILImageType

__all__ = ["PILLOW_SUFFIXES", "read_image_file"]

PILLOW_SUFFIXES = frozenset({".bmp", ".jfif", ".jpe", ".jpeg", ".jpg", ".png", ".webp"})
"""The suffixes for which imageio tries its Pillow plugin first (``imageio.config``)."""

_PILLOW_FORMATS = frozenset({"BMP", "JPEG", "PNG", "WEBP"})
_PILLOW_MODES = frozenset({"1", "CMYK", "I;16", "L", "LA", "P", "RGB", "RGBA"})
# Pillow's OSErrors, and tifffile's ValueError ("failed to read 4096 bytes, got 1920")
_TRUNCATED = ("image file is truncated", "Truncated File Read", "failed to read ")
_NEEDS_CODECS = "requires the 'imagecodecs' package"  # tifffile, for LZW, JPEG, ZSTD ...
_NO_READER = "Could not find a backend to open"  # imageio's OSError: no plugin reads the file


def read_image_file(file: Path) -> np.ndarray:
    """The pixels of an image file, dtype as stored, as ``imageio.v3.imread`` gives them.

    A photograph whose EXIF Orientation says it was taken turned (a phone held
    sideways) is turned upright, as viewers and OpenCV's ``imread`` show it. A
    CMYK image is converted to RGB (see :func:`_cmyk_as_rgb`); a stack of
    one frame (a still GIF) is that frame; an animation or a multi-page file
    (GIF, APNG, TIFF, WebP) is refused. The shape the header declares is checked
    against the pixel budget before anything is decoded, with Pillow's own
    decompression-bomb limit lifted meanwhile (one limit: the run's).

    Raises
    ------
    PermissionError
        When the file cannot be read.
    InputError
        When the header declares more pixels than the budget.
    ValueError
        When the file is not an image (saying when it is empty or
        truncated), holds several frames, or is CMYK with a colour profile
        that cannot be applied.
    """
    from PIL import Image as PILImage

    turn = 1  # as stored, unless Pillow read the file (or imageio did with Pillow) and EXIF says
    try:
        with _pillow_checks_left_to_the_budget():
            try:
                image = PILImage.open(_contents(file))
            except PILImage.UnidentifiedImageError:
                data = _read_with_imageio(file, None)
            else:
                with image:
                    _refuse_several_frames(file, image)
                    if _imageio_reads_as_pillow_does(file, image):
                        data = _read_with_pillow(file, image)
                    else:
                        data = _read_with_imageio(file, image)
                    if file.suffix.lower() in PILLOW_SUFFIXES:  # (another reader may turn it)
                        turn = _orientation(image)
    except (PermissionError, _FramesError, _ColourError, InputError):
        raise
    except Exception as error:  # Pillow and imageio raise many types for undecodable files
        reason = _what_is_wrong(file, error)
        raise ValueError(f"{file} is not a readable image ({reason})") from None
    data = data[0] if _one_frame_stack(data.shape) else data
    return _upright(data, turn) if turn in _UPRIGHT else data


_WHOLE = 64 << 20
"""Files of at most this many bytes are read whole before Pillow parses them."""


def _contents(file: Path) -> Path | io.BytesIO:
    """``file``'s bytes in memory, or ``file`` itself when it holds more than :data:`_WHOLE`
    or when Pillow will not decode it (a suffix imageio reads from the path itself: TIFF).

    Pillow reading a PNG from its path made about 15 system calls (a ``read`` and ``lseek``
    per chunk, ``fstat``, an ``ioctl``), each releasing the GIL and taking it again (a wait
    on threads); here five (:func:`graphvision.read_file_bytes`: open, fstat, read, the read
    that finds the end, close), which also keeps the SHA-256 of the bytes for the run's
    provenance (the file is not read again to hash it)."""
    if file.suffix.lower() not in PILLOW_SUFFIXES:
        return file
    data = read_file_bytes(file, _WHOLE)
    return file if data is None else io.BytesIO(data)


_ORIENTATION_TAG = 0x0112
"""EXIF's Orientation: how the stored pixels are turned from the scene upright (1: as
stored; 2 to 8: mirrored and/or rotated, as a phone held sideways or upside down saves)."""

_UPRIGHT = {
    2: lambda data: data[:, ::-1],
    3: lambda data: data[::-1, ::-1],
    4: lambda data: data[::-1],
    5: lambda data: data.swapaxes(0, 1),
    6: lambda data: np.rot90(data, -1),
    7: lambda data: data[::-1, ::-1].swapaxes(0, 1),
    8: lambda data: np.rot90(data, 1),
}
"""The pixels of an image whose Orientation is the key, turned upright (as a camera app,
a browser, Pillow's ``ImageOps.exif_transpose`` and OpenCV's ``imread`` show them)."""


def _orientation(image: PILImageType) -> int:
    """The EXIF Orientation of an image read through ``image`` (1 without one); the EXIF
    of a PNG whose eXIf chunk follows its pixels is known once they are decoded; a damaged
    EXIF block (Pillow's parser raises struct.error, SyntaxError...) says nothing: 1."""
    if "exif" not in image.info:
        return 1
    try:
        value = image.getexif().get(_ORIENTATION_TAG, 1)
    except Exception:  # the pixels are whole: read them as stored, as before EXIF was read
        return 1
    return value if isinstance(value, int) else 1


def _upright(data: np.ndarray, turn: int) -> np.ndarray:
    """``data`` turned upright from EXIF Orientation ``turn`` (2 to 8): a new C-ordered,
    writeable array."""
    return np.ascontiguousarray(_UPRIGHT[turn](data))


def _one_frame_stack(shape: tuple[int, ...]) -> bool:
    """Whether ``shape`` is a stack of one frame, (1, H, W[, C]), as imageio reads a still
    GIF: the frame is the image."""
    return len(shape) >= 3 and shape[0] == 1 and (len(shape) == 4 or shape[-1] not in (2, 3, 4))


_PAGED_FORMATS = frozenset({"GIF", "PNG", "TIFF", "WEBP"})
"""Formats whose frames are an animation's or a document's pages (MPO's second frame is a
camera's other view or preview: its first is the photograph, as imageio reads it)."""


def _refuse_several_frames(file: Path, image: PILImageType) -> None:
    """Refuse an animation or a multi-page file from its Pillow handle (a multi-page TIFF
    read as a stack, an animated WebP read as its first frame, went unnoticed)."""
    if image.format in _PAGED_FORMATS:
        frames = getattr(image, "n_frames", 1)
        if frames > 1:
            raise _several_frames(file, frames, "page" if image.format == "TIFF" else "index")


def _several_frames(file: Path, frames: int, pick: str = "index") -> _FramesError:
    """What to do with a file of several frames; ``pick``: imageio's argument that reads
    one of them (a TIFF's ``index`` is a whole series, its ``page`` one page)."""
    return _FramesError(
        f"{file} holds {frames} frames (an animation or a multi-page file); "
        "graphvision reads one still image: save the frame you want as PNG "
        f"(e.g. imageio.v3.imwrite('frame.png', imageio.v3.imread(path, {pick}=0))) "
        "or run --batch over the frames saved as files"
    )


def _imageio_reads_as_pillow_does(file: Path, image: PILImageType) -> bool:
    """Whether ``iio.imread(file)`` would be ``np.asarray`` of ``image`` (its palette
    expanded): imageio picks Pillow for the suffix, reads one frame of the format
    (not GIF, not APNG) and converts nothing else in that mode."""
    return (
        file.suffix.lower() in PILLOW_SUFFIXES
        and image.format in _PILLOW_FORMATS
        and image.mode in _PILLOW_MODES
        and getattr(image, "custom_mimetype", None) != "image/apng"
    )


def _read_with_pillow(file: Path, image: PILImageType) -> np.ndarray:
    """The pixels of an open ``image``, after its header's shape passed the budget."""
    from PIL.Image import getmodebands

    palette = image.palette if image.mode == "P" else None
    mode = palette.mode if palette is not None else image.mode  # what it decodes to
    bands = getmodebands(mode)  # the shape iio.improps declares: (H, W), or (H, W, bands)
    check_pixels((image.height, image.width, *((bands,) if bands > 1 else ())), str(file))
    if image.mode == "CMYK":
        return _cmyk_as_rgb(file, image)
    if palette is not None:  # as imageio's Pillow plugin does (Pillow 9 changed palettes)
        image = image.convert(mode)
    data = np.asarray(image)
    return data if data.flags.writeable else data.copy()  # writeable, as imageio's is


def _read_with_imageio(file: Path, image: PILImageType | None) -> np.ndarray:
    """The pixels ``iio.imread`` gives, after imageio's header passed the budget and
    showed one frame; a CMYK ``image`` (Pillow's handle on the file) converted to RGB."""
    import imageio.v3 as iio

    properties = iio.improps(file)  # the header only: nothing is decoded yet
    shape = tuple(properties.shape)
    check_pixels(shape[1:] if _one_frame_stack(shape) else shape, str(file))
    frames = properties.n_images
    if frames is not None and frames > 1:
        raise _several_frames(file, frames)
    if image is not None and image.mode == "CMYK":
        return _cmyk_as_rgb(file, image)
    data: np.ndarray = iio.imread(file)
    return data


def _what_is_wrong(file: Path, error: Exception) -> str:
    """Why a file is not a readable image: in words where known, else the error's type."""
    from ._unreadable import size_zero_reason, tiff_data_cut

    with contextlib.suppress(OSError):
        size = file.stat().st_size
        if size == 0:  # (empty, or a file of /proc: bytes, and a size of 0)
            return size_zero_reason(file)
        if cut := _truncated_header(file):
            return f"the file is truncated: {cut}"
        if str(error).startswith(_TRUNCATED) or tiff_data_cut(file, size):
            return f"the file is truncated: its {size:,} bytes end before the image does"
    if str(error).startswith(_NO_READER):
        return "neither Pillow nor imageio knows its format: save it as PNG, JPEG or TIFF"
    if _NEEDS_CODECS in str(error):  # tifffile: "<COMPRESSION.LZW: 5> requires the ..."
        compression = str(error).split(_NEEDS_CODECS)[0].strip()
        return (
            f"its compression, {compression}, is decoded by tifffile only with the imagecodecs "
            "package: pip install imagecodecs, or save it uncompressed"
        )
    return type(error).__name__


_SIGNATURES = (
    (b"\x89PNG\r\n\x1a\n", "PNG"),
    (b"\xff\xd8\xff", "JPEG"),
    (b"GIF87a", "GIF"),
    (b"GIF89a", "GIF"),
    (b"BM", "BMP"),
    (b"II*\x00", "TIFF"),
    (b"MM\x00*", "TIFF"),
    (b"RIFF", "WEBP"),  # (then the size, then "WEBP")
)
"""The first bytes of each format graphvision reads, and Pillow's name of the format."""


def _truncated_header(file: Path) -> str:
    """What is missing when ``file`` begins a format's header but does not complete it,
    or ''.

    A file that begins a format's signature (or is a part of one) and on which
    Pillow's parser of that format asked for bytes beyond the end (a PNG cut in
    its ``IHDR`` chunk, a JPEG before its frame marker) is a truncated file: the
    parsers say ``SyntaxError``, ``IndexError`` or ``struct.error`` there, which
    name no cause. A header that is whole but damaged (a wrong checksum) is not.
    A WebP file (a RIFF container) is cut when it is shorter than the size its
    first 8 bytes declare.
    """
    with contextlib.suppress(OSError):
        data = file.read_bytes()
        count = f"{len(data):,} byte{'s' if len(data) > 1 else ''}"
        for signature, kind in _SIGNATURES:
            if not signature.startswith(data[: len(signature)]):
                continue
            if kind == "WEBP" and b"WEBP".startswith(data[8:12]):
                declared = 8 + int.from_bytes(data[4:8], "little")
                if len(data) < 12:
                    return f"not a complete WebP header ({count})"
                if len(data) < declared:
                    return f"its WebP header declares {declared:,} bytes, it holds {count}"
            elif kind != "WEBP" and (len(data) <= len(signature) or _header_runs_out(data, kind)):
                return f"not a complete {kind} header ({count})"
    return ""


class _EndWatch(io.BytesIO):
    """A file's bytes that note when a read asked for more than was left, the first read
    aside (``Image.open`` reads 16 bytes to pick the parsers to try)."""

    reads = 0
    ran_out = False

    def read(self, size: int | None = -1, /) -> bytes:
        data = super().read(size)
        self.reads += 1
        if self.reads > 1 and size is not None and size > len(data):
            self.ran_out = True
        return data


def _header_runs_out(data: bytes, kind: str) -> bool:
    """Whether Pillow's parser of format ``kind`` read to the end of ``data`` and wanted
    more, parsing its header (nothing is decoded)."""
    from PIL import Image as PILImage

    stream = _EndWatch(data)
    with contextlib.suppress(Exception), PILImage.open(stream, formats=[kind]):
        pass
    return stream.ran_out


class _LiftedLimit:
    """Pillow's limit is one global for the process: the first reader lifts it, the last
    puts back what the first found (each reader saving and restoring it alone, readers on
    two threads left it lifted for good, the user's own ``Image.open`` unprotected)."""

    lock = threading.Lock()
    readers = 0
    before: int | None = None


@contextlib.contextmanager
def _pillow_checks_left_to_the_budget() -> Iterator[None]:
    """Pillow's own decompression-bomb limit (89 megapixels, a warning, then an error at
    twice that) lifted while a file the budget admitted is read: one limit, the run's."""
    from PIL import Image as PILImage

    with _LiftedLimit.lock:
        if _LiftedLimit.readers == 0:
            _LiftedLimit.before = PILImage.MAX_IMAGE_PIXELS
            PILImage.MAX_IMAGE_PIXELS = None
        _LiftedLimit.readers += 1
    try:
        yield
    finally:
        with _LiftedLimit.lock:
            _LiftedLimit.readers -= 1
            if _LiftedLimit.readers == 0:
                PILImage.MAX_IMAGE_PIXELS = _LiftedLimit.before


class _FramesError(ValueError):
    """A file with several frames where one image is expected."""


class _ColourError(ValueError):
    """A colour space that cannot be converted to RGB correctly."""


def _cmyk_as_rgb(file: Path, image: PILImageType) -> np.ndarray:
    """The RGB pixels of a CMYK ``image`` (Pillow's open handle on ``file``).

    With an embedded ICC profile the pixels go through it to sRGB
    (LittleCMS, via Pillow's ``ImageCms``); a profile that cannot build that
    transform is refused by name. Without one, Pillow's device conversion
    R = 255 - min(255, C + K) (likewise G, B) is the definition; Pillow
    undoes the inverted CMYK of Adobe JPEGs when it reads them.

    Raises
    ------
    ValueError
        For a CMYK image whose embedded colour profile cannot be applied.
    """
    from PIL import ImageCms

    profile = image.info.get("icc_profile")
    if not profile:
        return np.asarray(image.convert("RGB"))
    try:
        converted = ImageCms.profileToProfile(
            image,
            ImageCms.ImageCmsProfile(io.BytesIO(profile)),
            ImageCms.createProfile("sRGB"),
            outputMode="RGB",
        )
    except (ImageCms.PyCMSError, OSError) as error:
        raise _ColourError(
            f"{file} is a CMYK image whose embedded colour profile cannot be applied "
            f"({error}); convert it to RGB with a colour-managed tool first"
        ) from None
    return np.asarray(converted)
