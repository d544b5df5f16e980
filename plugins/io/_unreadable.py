"""What is wrong with an image file that could not be read, where the readers' own errors
do not say it in words.

A TIFF cut inside its pixel data, whatever its layout: tifffile says so in
words only for uncompressed strips ("failed to read 4096 bytes, got 1920"); cut
inside zlib-compressed strips it raises zlib's ``error`` ("incomplete or
truncated stream"), inside tiles a ``TiffFileError`` ("corrupted tile ...
cannot be reshaped"). The file's own tags say where its strips or tiles end: a
file shorter than that was cut, whatever the codec.

An empty file: its size is 0, and so is that of files the kernel writes as they
are read (``/proc/self/status``, a link to it): a file is empty when reading it
gives no byte, not when its size says 0.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["size_zero_reason", "tiff_data_cut"]


def tiff_data_cut(file: Path, size: int) -> bool:
    """Whether ``file`` (of ``size`` bytes) is a TIFF whose first page's strips or tiles,
    as its StripOffsets/TileOffsets and byte counts declare them, end past its last byte.

    False for a file that is not a TIFF or whose tags cannot be read (its header is
    cut: :func:`~._image_file._truncated_header` says so).
    """
    import tifffile

    try:
        with tifffile.TiffFile(file) as tiff:
            page = tiff.pages[0]
            ends = [
                offset + count
                for offset, count in zip(page.dataoffsets, page.databytecounts, strict=False)
                if count
            ]
    except Exception:  # not a TIFF, or tags tifffile cannot read: nothing to say here
        return False
    return bool(ends) and max(ends) > size


def size_zero_reason(file: Path) -> str:
    """Why ``file``, whose size says 0 and which no reader took, is no image: empty when
    reading it gives no byte; else a file the system writes as it is read (``/proc``'s),
    whose bytes Pillow did not know as an image (imageio cannot seek in it)."""
    with file.open("rb") as handle:
        if not handle.read(1):
            return "the file is empty"
    return (
        "its size reads 0 but it holds bytes, which are no image Pillow knows: a file the "
        "system writes as it is read (as those of /proc are) is not an image file"
    )
