"""Image comparison: mean squared error and PSNR."""

from ._quality import mse, psnr

__all__ = ["mse", "psnr"]
