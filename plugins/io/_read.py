"""Reading sample images and image files."""

from __future__ import annotations

from pathlib import Path
from typing import Literal, get_args

import numpy as np

from graphvision import Image, node, source

from .._checks import to_float_image

__all__ = ["SAMPLES", "read_file", "read_sample", "sample"]

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
    "page",
    "rocket",
    "text",
]
SAMPLES: tuple[str, ...] = get_args(SampleName)


@source("sample")
def read_sample(name: str) -> np.ndarray:
    """Load ``skimage.data.<name>()`` as a float32 image (shipped with scikit-image, offline).

    Raises
    ------
    ValueError
        For a name that is not one of :data:`SAMPLES`, with the list.
    """
    if name not in SAMPLES:
        import difflib

        close = difflib.get_close_matches(name, SAMPLES, n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise ValueError(f"unknown sample image '{name}'{hint}; samples: {', '.join(SAMPLES)}")
    import skimage.data

    return to_float_image(getattr(skimage.data, name)(), source=f"sample '{name}'")


@source("file")
def read_file(path: str) -> np.ndarray:
    """Read an image file (any format imageio reads) or a ``.npy`` array.

    Raises
    ------
    FileNotFoundError, PermissionError
        With the path.
    ValueError
        When the file is not an image, or the image is empty or has an
        unsupported shape or dtype.
    """
    file = Path(path)
    if file.is_dir():
        raise IsADirectoryError(f"{file} is a folder, not an image file")
    if not file.is_file():
        raise FileNotFoundError(f"no such file: {file}")
    if file.suffix.lower() == ".npy":
        try:
            data = np.load(file, allow_pickle=False)
        except ValueError as error:
            raise ValueError(f"{file} is not a plain numpy array file: {error}") from None
        return to_float_image(data, source=str(file))
    import imageio.v3 as iio

    try:
        data = iio.imread(file)
    except PermissionError:
        raise
    except Exception as error:  # imageio raises many types for undecodable files
        raise ValueError(f"{file} is not a readable image ({type(error).__name__})") from None
    if data.ndim == 3 and data.shape[0] in (1,) and data.shape[2] not in (2, 3, 4):
        data = data[0]
    return to_float_image(data, source=str(file))


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
