"""Parameter types shared by the built-in plugins: seeds, probabilities, fractions, odd sizes.

Each is an ``Annotated`` alias that pydantic validates and a type checker reads as
``int`` or ``float``. A family that bounds an odd size writes the bounds before the
check, ``Annotated[int, Field(ge=1, le=31), AfterValidator(odd)]``: constraints
after a validator are enforced but left out of the JSON Schema. A refused value
is reported by the engine with the node and the parameter's name, so the
messages here say only what is wrong with the value.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator, Field

__all__ = [
    "MAX_EPOCHS",
    "MAX_ITERATIONS",
    "MAX_SIDE",
    "Count",
    "Epochs",
    "Fraction",
    "ImageSide",
    "Iterations",
    "OddSize",
    "Positive",
    "Probability",
    "ScaleFactor",
    "Seed",
    "odd",
]

MAX_EPOCHS = 1000
"""Most passes over a training set: a NumPy network on this machine takes seconds per
epoch, so more would run for hours (and the small training sets here converge in tens)."""

MAX_ITERATIONS = 1_000_000
r"""Most iterations of an iterative fit (RANSAC hypotheses, k-means, SVM, boosting
rounds). RANSAC's adaptive count :math:`\log(1 - p) / \log(1 - w^s)` is 105,000 for an
8-point sample at w = 30 % inliers and p = 99.9 % confidence; a million takes about a
minute, more only makes a run that never ends."""

MAX_SIDE = 8192
"""Largest side of an image a node makes (a warp's output, a rendered camera view): a
float64 8192 × 8192 colour image is 1.5 GiB."""


def odd(size: int) -> int:
    """``size`` itself if it is odd, else ValueError: a window needs a centre pixel."""
    if size % 2 == 0:
        raise ValueError(f"must be odd so the window is centred on a pixel, got {size}")
    return size


Seed = Annotated[int, Field(ge=0, description="Seed of the random generator.")]
"""Seed of a NumPy random generator (``numpy.random.default_rng(seed)``)."""

Probability = Annotated[float, Field(gt=0, lt=1)]
"""A probability strictly between 0 and 1 (a RANSAC confidence, a held-out fraction)."""

Fraction = Annotated[float, Field(ge=0, le=1)]
"""A fraction or an overlap in [0, 1] (an IoU, a relative threshold, a score)."""

Positive = Annotated[float, Field(gt=0)]
"""A length, a tolerance or a scale: greater than 0."""

Count = Annotated[int, Field(ge=1)]
"""A number of things or iterations: at least 1."""

Epochs = Annotated[int, Field(ge=1, le=MAX_EPOCHS)]
"""Passes over a training set: 1 to ``MAX_EPOCHS``."""

Iterations = Annotated[int, Field(ge=1, le=MAX_ITERATIONS)]
"""Most iterations of an iterative fit: 1 to ``MAX_ITERATIONS``."""

ImageSide = Annotated[int, Field(ge=1, le=MAX_SIDE)]
"""The side of an image a node makes, in pixels: 1 to ``MAX_SIDE``."""

ScaleFactor = Annotated[float, Field(ge=0.125, le=1024)]
"""A factor an image is shrunk by, 1/8 to 1,024: below 1 it is enlarged, and 1/8 makes it
64 times larger in area already (a 512 × 512 image becomes 4096 × 4096)."""

OddSize = Annotated[int, Field(ge=1), AfterValidator(odd)]
"""The side of a window centred on a pixel: odd, at least 1."""
