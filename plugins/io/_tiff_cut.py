"""Whether a TIFF file was cut inside its pixel data, whatever its layout.

tifffile says so in words only for uncompressed strips ("failed to read 4096
bytes, got 1920"); cut inside zlib-compressed strips it raises zlib's
``error`` ("incomplete or truncated stream"), inside tiles a ``TiffFileError``
("corrupted tile ... cannot be reshaped"). The file's own tags say where its
strips or tiles end: a file shorter than that was cut, whatever the codec.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["tiff_data_cut"]


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
