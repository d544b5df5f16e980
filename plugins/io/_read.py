"""Reading sample images and image files."""

from __future__ import annotations

import contextlib
import functools
import io
from collections.abc import Iterator
from pathlib import Path
from typing import Literal, get_args

import numpy as np

from graphvision import Image, InputError, check_array_file, check_pixels, node, source

from ..shared.checks import to_float_image

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
    since a graph input is one still image.

    Raises
    ------
    FileNotFoundError, PermissionError, IsADirectoryError
        With the path.
    ValueError
        When the file is not an image, holds several frames, or is CMYK
        with a colour profile that cannot be applied.
    """
    file = Path(path)
    if file.is_dir():
        raise IsADirectoryError(f"{file} is a folder, not an image file")
    if not file.exists():
        raise FileNotFoundError(f"no such file: {file}")
    if not file.is_file():  # a device, a pipe, a socket: endless or blocking to read
        raise ValueError(f"{file} is not a regular file (a device, pipe or socket)")
    if file.suffix.lower() == ".npy":
        try:
            check_array_file(file)  # what its header declares, within the budget, first
            array: np.ndarray = np.load(file, allow_pickle=False)
        except ValueError as error:
            raise ValueError(f"{file} is not a plain numpy array file: {error}") from None
        return array
    import imageio.v3 as iio

    try:
        with _pillow_checks_left_to_the_budget():
            properties = iio.improps(file)  # the header only: nothing is decoded yet
        check_pixels(properties.shape, str(file))
        frames = properties.n_images
        if frames is not None and frames > 1:
            raise _FramesError(
                f"{file} holds {frames} frames (an animation or a multi-page file); "
                "graphvision reads one still image: save the frame you want as PNG "
                "(e.g. imageio.v3.imwrite('frame.png', imageio.v3.imread(path, index=0))) "
                "or run --batch over the frames saved as files"
            )
        with _pillow_checks_left_to_the_budget():
            cmyk = _cmyk_as_rgb(file)
            data: np.ndarray = iio.imread(file) if cmyk is None else cmyk
    except (PermissionError, _FramesError, _ColourError, InputError):
        raise
    except Exception as error:  # imageio raises many types for undecodable files
        raise ValueError(f"{file} is not a readable image ({type(error).__name__})") from None
    if data.ndim == 3 and data.shape[0] in (1,) and data.shape[2] not in (2, 3, 4):
        data = data[0]
    return data


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


@contextlib.contextmanager
def _pillow_checks_left_to_the_budget() -> Iterator[None]:
    """Pillow's own decompression-bomb limit (89 megapixels, a warning, then an error at
    twice that) lifted while a file the budget admitted is read: one limit, the run's."""
    from PIL import Image as PILImage

    before = PILImage.MAX_IMAGE_PIXELS
    PILImage.MAX_IMAGE_PIXELS = None
    try:
        yield
    finally:
        PILImage.MAX_IMAGE_PIXELS = before


class _FramesError(ValueError):
    """A file with several frames where one image is expected."""


class _ColourError(ValueError):
    """A colour space that cannot be converted to RGB correctly."""


def _cmyk_as_rgb(file: Path) -> np.ndarray | None:
    """The RGB pixels of a CMYK image, or None for any other mode.

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
    from PIL import Image as PILImage
    from PIL import ImageCms

    try:
        with PILImage.open(file) as image:
            if image.mode != "CMYK":
                return None
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
    except PILImage.UnidentifiedImageError:
        return None


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
