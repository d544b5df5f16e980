"""One pixel budget for every image and array a run reads, checked before anything is decoded.

A compressed file can declare far more than it holds: a 6 MB ``.npz`` may
declare a 40,000 × 40,000 float32 array (6 GB once inflated), a PNG of a few
kilobytes a 400-megapixel image. Readers therefore look at what a file
declares (an ``.npy`` header, each member's header inside an ``.npz``, an
image's header) and refuse, naming the file, what it declares and how to
raise the budget, before they inflate a byte of it.

The budget counts pixels: an array's elements, except that the last axis of
an ``H×W×C`` image with at most four channels is not counted (an RGB image
of 100 megapixels is 100 megapixels). It is, in order: the ``max_pixels`` of
the run (``gv.run(..., max_pixels=...)``), the ``GRAPHVISION_MAX_PIXELS``
environment variable (which ``--max-pixels`` sets, so worker processes and a
local Dask cluster see it too), or :data:`DEFAULT_MAX_PIXELS`.
"""

from __future__ import annotations

import contextlib
import os
import zipfile
from collections.abc import Iterator
from contextvars import ContextVar
from pathlib import Path
from typing import IO

import numpy as np

from graphvision.errors import InputError

__all__ = [
    "DEFAULT_MAX_PIXELS",
    "ENVIRONMENT_VARIABLE",
    "check_array_file",
    "check_pixels",
    "max_pixels",
    "npy_declared",
    "npz_declared",
    "pixel_budget",
    "pixel_count",
    "pixels_of",
]

DEFAULT_MAX_PIXELS = 100_000_000
"""100 megapixels: an RGB float32 image of 1.2 GB, several of which a pipeline holds at
once on a 24 GB machine (a 120-megapixel photograph took 5 GB and 31 s in a pipeline)."""

ENVIRONMENT_VARIABLE = "GRAPHVISION_MAX_PIXELS"

_BUDGET: ContextVar[int | None] = ContextVar("graphvision_max_pixels", default=None)


def max_pixels() -> int:
    """The pixel budget in force (see the module docstring for where it comes from).

    Raises
    ------
    InputError
        When the budget comes from :data:`ENVIRONMENT_VARIABLE` and it is not a whole
        number above 0 (``gv.run``, ``gv.run_batch``, ``gv.sweep`` and the commands that
        run ask before any work: :func:`graphvision.execution.arguments.run_arguments`).
    """
    given = _BUDGET.get()
    if given is not None:
        return given
    text = os.environ.get(ENVIRONMENT_VARIABLE, "")
    if not text:
        return DEFAULT_MAX_PIXELS
    try:
        return pixel_count(text)
    except ValueError:  # (-1 made every image "over a budget of -1 pixels")
        raise InputError(
            f"{ENVIRONMENT_VARIABLE}={text!r} is not a whole number of pixels above 0 "
            f"(e.g. 2e8; unset, the budget is {DEFAULT_MAX_PIXELS:,})"
        ) from None


def pixel_count(text: str) -> int:
    """A pixel budget written as ``--max-pixels`` and :data:`ENVIRONMENT_VARIABLE` take it:
    a whole number of at least 1 (``1e9`` and ``1_000_000`` accepted).

    >>> pixel_count("1e9"), pixel_count("1_000_000")
    (1000000000, 1000000)

    Raises
    ------
    ValueError
        Saying what is wrong with ``text``.
    """
    try:
        value = int(float(text)) if "e" in text.lower() else int(text)
    except (ValueError, OverflowError):  # (float("1e999") is inf)
        raise ValueError(f"not a whole number of pixels: '{text}'") from None
    if value <= 0:
        raise ValueError(f"must be at least 1, got {value}")
    return value


def pixel_budget(pixels: int | None) -> contextlib.AbstractContextManager[None]:
    """Within the block, :func:`max_pixels` is ``pixels`` (None: unchanged, and nothing is
    entered: a generator made and run per run was a microsecond of each)."""
    return _UNCHANGED if pixels is None else _budget(pixels)


_UNCHANGED = contextlib.nullcontext()


@contextlib.contextmanager
def _budget(pixels: int) -> Iterator[None]:
    if not isinstance(pixels, int) or isinstance(pixels, bool) or pixels < 1:
        raise TypeError(f"max_pixels must be a positive whole number, got {pixels!r}")
    token = _BUDGET.set(pixels)
    try:
        yield
    finally:
        _BUDGET.reset(token)


def pixels_of(shape: tuple[int, ...]) -> int:
    """Pixels of an array of ``shape``: its elements, the channels of an image not counted."""
    count = int(np.prod(shape, dtype=np.int64)) if shape else 1
    if len(shape) == 3 and 1 <= shape[2] <= 4:
        count //= shape[2]
    return count


def check_pixels(shape: tuple[int, ...], what: str) -> None:
    """Refuse ``what`` (a file, a member of one) when ``shape`` exceeds the pixel budget.

    Raises
    ------
    InputError
        Naming ``what``, its declared size and the budget, and how to raise it.
    """
    pixels, budget = pixels_of(tuple(int(n) for n in shape)), max_pixels()
    if pixels > budget:
        size = " × ".join(str(int(n)) for n in shape)
        raise InputError(
            f"{what} declares {size} ({_amount(pixels)}), over the pixel budget of "
            f"{_amount(budget)}; nothing was decoded. Raise the budget with "
            f"--max-pixels N (gv.run(..., max_pixels=N), or {ENVIRONMENT_VARIABLE}=N) if "
            "the machine has the memory"
        )


def _amount(pixels: int) -> str:
    return f"{pixels / 1e6:,.1f} megapixels" if pixels >= 1_000_000 else f"{pixels:,} pixels"


def npy_declared(stream: IO[bytes]) -> tuple[tuple[int, ...], np.dtype]:
    """Shape and dtype an ``.npy`` stream's header declares (the stream is left after it).

    Raises
    ------
    ValueError
        When the stream is not an ``.npy`` file.
    """
    from numpy.lib import format as npy

    version = npy.read_magic(stream)
    read_header = {
        (1, 0): npy.read_array_header_1_0,
        (2, 0): npy.read_array_header_2_0,
    }.get(version)
    if read_header is None:
        raise ValueError(f"unsupported .npy format version {version}")
    shape, _, dtype = read_header(stream)
    return tuple(shape), np.dtype(dtype)


def npz_declared(path: Path) -> dict[str, tuple[tuple[int, ...], np.dtype]]:
    """Each member's shape and dtype, read from its header without inflating the rest.

    Raises
    ------
    ValueError
        When the file is not a zip of ``.npy`` members.
    """
    declared = {}
    try:
        with zipfile.ZipFile(path) as archive:
            for member in archive.namelist():
                if not member.endswith(".npy"):
                    continue
                with archive.open(member) as stream:
                    declared[member[: -len(".npy")]] = npy_declared(stream)
    except zipfile.BadZipFile as error:
        raise ValueError(f"{path} is not an .npz archive ({error})") from None
    return declared


def check_array_file(path: Path) -> None:
    """Refuse an ``.npy`` or ``.npz`` file whose declared arrays exceed the pixel budget."""
    if path.suffix.lower() == ".npz":
        for name, (shape, _) in npz_declared(path).items():
            check_pixels(shape, f"{path} (array '{name}')")
    elif path.suffix.lower() == ".npy":
        with path.open("rb") as stream:
            shape, _ = npy_declared(stream)
        check_pixels(shape, str(path))
