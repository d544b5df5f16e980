"""Reading sample images and image files."""

from __future__ import annotations

import errno
import functools
import os
import stat
from pathlib import Path
from typing import Literal, get_args

import numpy as np

from graphvision import Image, check_array_file, node, source

from ..shared.checks import to_float_image
from ._image_file import read_image_file

__all__ = ["SAMPLES", "read_array", "read_file", "read_sample", "sample", "sample_array"]

SampleName = Literal[
    "astronaut",
    "brick",
    "camera",
    "cat",
    "checkerboard",
    "clock",
    "coffee",
    "coins",
    "grass",
    "gravel",
    "horse",
    "moon",
    "motorcycle_disparity",
    "motorcycle_left",
    "motorcycle_right",
    "page",
    "rocket",
    "text",
]
SAMPLES: tuple[str, ...] = get_args(SampleName)


def sample_key(name: str) -> str:
    """What fixes a sample's pixels without loading it: its name and scikit-image's version."""
    check_sample_name(name)
    return f"skimage.data.{name} scikit-image=={_scikit_image_version()}"


@functools.cache
def _scikit_image_version() -> str:
    """The installed scikit-image's version, read once per process (reading the
    distribution's metadata took 3 ms of every run naming a sample)."""
    from importlib.metadata import version

    return version("scikit-image")


def check_sample_name(name: str) -> None:
    """Refuse a name that is not one of :data:`SAMPLES`, suggesting the closest."""
    if name not in SAMPLES:
        import difflib

        close = difflib.get_close_matches(name, SAMPLES, n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise ValueError(f"unknown sample image '{name}'{hint}; samples: {', '.join(SAMPLES)}")


@source("sample", key=sample_key)
def sample_array(name: str) -> np.ndarray:
    """``skimage.data.<name>()`` as shipped (uint8 or bool); the input's port applies the policy.

    ``motorcycle_left``, ``motorcycle_right`` and ``motorcycle_disparity`` are
    the parts of ``stereo_motorcycle()``: the rectified Middlebury 2014 pair
    and its ground-truth disparity (float32, NaN where unknown).

    Raises
    ------
    ValueError
        For a name that is not one of :data:`SAMPLES`, with the list.
    """
    check_sample_name(name)
    import skimage.data

    if name.startswith("motorcycle_"):  # the rectified Middlebury pair scikit-image ships
        left, right, disparity = skimage.data.stereo_motorcycle()
        if name.endswith("disparity"):  # ground truth, float32, inf where unknown -> NaN
            return np.where(np.isfinite(disparity), disparity, np.nan).astype(np.float32)
        return left if name.endswith("left") else right
    data: np.ndarray = getattr(skimage.data, name)()
    return data


def read_sample(name: str) -> np.ndarray:
    """Load ``skimage.data.<name>()`` as a float32 image (shipped with scikit-image, offline)."""
    return to_float_image(sample_array(name), source=f"sample '{name}'")


@source("file")
def read_array(path: str) -> np.ndarray:
    """Decode an image file (any format imageio reads) or a ``.npy`` array, dtype as stored.

    The graph input's port type then applies the dtype policy: a ``uint8``
    PNG becomes a ``float32`` image, a bool ``.npy`` a mask. A CMYK image
    (JPEG or TIFF from print workflows) is converted to RGB (through its
    embedded colour profile when it has one), not read as four RGBA
    channels. An animated or multi-page file is refused with what to do,
    since a graph input is one still image. A PNG, JPEG, BMP or WebP file is
    opened once, with Pillow: its header is checked against the pixel budget,
    then the same handle decodes it (:mod:`._image_file`); other formats are
    read with imageio.

    Raises
    ------
    FileNotFoundError, PermissionError, IsADirectoryError
        With the path.
    ValueError
        When the file is not an image (saying when it is empty or truncated),
        holds several frames, or is CMYK with a colour profile that cannot be
        applied.
    """
    file = Path(path)
    mode = _mode(file)
    if mode is not None and stat.S_ISDIR(mode):
        raise IsADirectoryError(f"{file} is a folder, not an image file")
    if mode is None:  # (a relative path is read from the working folder: say which)
        where = "" if file.is_absolute() else f" (looked for from the working folder {Path.cwd()})"
        raise FileNotFoundError(f"no such file: {file}{where}")
    if not stat.S_ISREG(mode):  # a device, a pipe, a socket: endless or blocking to read
        raise ValueError(f"{file} is not a regular file (a device, pipe or socket)")
    if file.suffix.lower() == ".npy":
        try:
            check_array_file(file)  # what its header declares, within the budget, first
            array: np.ndarray = np.load(file, allow_pickle=False)
        except ValueError as error:
            raise ValueError(f"{file} is not a plain numpy array file: {error}") from None
        return array
    return read_image_file(file)


_NOT_THERE = frozenset({errno.ENOENT, errno.ENOTDIR, errno.EBADF, errno.ELOOP})
"""What ``Path.exists`` takes for a path that is not there (other errors it raises)."""


def _mode(file: Path) -> int | None:
    """``file``'s mode (its target's, for a link), None when there is nothing there: one
    ``stat``, where ``is_dir``, ``exists`` and ``is_file`` made three, each releasing the
    GIL and taking it back (a wait on a batch on threads).

    Raises
    ------
    PermissionError
        When a folder on the way cannot be searched (as ``Path.exists`` raises it).
    """
    try:
        return os.stat(file).st_mode
    except ValueError:  # a NUL in the path: nothing there, as Path.exists says
        return None
    except OSError as error:
        if error.errno in _NOT_THERE:
            return None
        raise


def read_file(path: str) -> np.ndarray:
    """An image file or ``.npy`` array as a float32 image: :func:`read_array`, then the policy.

    Raises
    ------
    FileNotFoundError, PermissionError, IsADirectoryError
        With the path.
    ValueError
        When the file is not an image, or the image is empty or has an
        unsupported shape or dtype.
    """
    return to_float_image(read_array(path), source=str(path))


@node("io.sample", version=1)
def sample(*, name: SampleName = "camera") -> Image:
    """A sample image shipped with scikit-image, as float32 in [0, 1].

    Parameters
    ----------
    name : str
        One of astronaut, brick, camera, cat, checkerboard, clock, coffee,
        coins, grass, gravel, horse, moon, page, rocket, text.

    Returns
    -------
    image : (H, W) or (H, W, 3) float32 ndarray

    References
    ----------
    .. [1] scikit-image ``skimage.data``: https://scikit-image.org/docs/stable/api/skimage.data.html
    """
    return read_sample(name)
