"""Colour: grayscale conversion and normalised rgb chromaticity."""

from ._color import LUMINANCE_WEIGHTS, chromaticity, to_gray

__all__ = ["LUMINANCE_WEIGHTS", "chromaticity", "to_gray"]
